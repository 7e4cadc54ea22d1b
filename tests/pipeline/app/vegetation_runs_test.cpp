// Runs over real vegetation (PRODUCT.md section 8, issue 24).
//
// terrain: {"point_cloud": true}: the ground of canopy.point_cloud's cloud, gridded as `glaswave
// voxelize` grids it, is the run's terrain without a DEM file. Clouds of ground points on a level
// and a tilted plane give it back within the 2 cm; a shot at nadir over the level one
// returns the bare-ground closed form of PHYSICS.md section 1 from the plane's height; and the key
// is refused without a point cloud or beside another ground.
//
// Each source (voxels, point cloud, facets) gives the same products for --threads 1 and 2, a
// --shots split, mpirun -np 2 and --resume after a SIGKILL (PRODUCT.md section 2).
#include <gtest/gtest.h>
#include <netcdf.h>
#include <ogr_spatialref.h>

#include <cmath>
#include <fstream>
#include <memory>
#include <numbers>
#include <string>

#include "canopy/cloud_terrain.hpp"
#include "pipeline/engine/inputs.hpp"
#include "tests/canopy/las_fixture.hpp"
#include "tests/pipeline/app/product_compare.hpp"
#include "tests/pipeline/app/run_control.hpp"
#include "tests/pipeline/engine/engine_test_support.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

namespace fs = std::filesystem;

constexpr double x0_m = 500000.0, y0_m = 4982950.0;  // UTM 33N, near 45 N 15 E
constexpr double side_m = 200.0, ground_m = 300.0;

std::string utm33_wkt() {
  OGRSpatialReference utm;
  utm.importFromEPSG(32633);
  char* text = nullptr;
  utm.exportToWkt(&text);
  const std::string wkt(text);
  CPLFree(text);
  return wkt;
}

// Longitude and latitude of UTM 33N points, by OGR (PROJ), not by glaswave's own transforms.
class ToLonLat {
 public:
  ToLonLat() {
    utm_.importFromEPSG(32633);
    wgs84_.importFromEPSG(4326);
    wgs84_.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    transform_.reset(OGRCreateCoordinateTransformation(&utm_, &wgs84_));
  }
  std::array<double, 2> operator()(double x, double y) const {
    transform_->Transform(1, &x, &y);
    return {x, y};
  }

 private:
  OGRSpatialReference utm_, wgs84_;
  std::unique_ptr<OGRCoordinateTransformation> transform_;
};

// Where a cloud's point of lattice node (i, j) lies: up to 0.4 m off the node, as scans fall
// (a regular lattice is the Delaunay triangulation's worst case, all its points cocircular).
std::array<double, 2> scattered(int i, int j) {
  const auto frac = [](double v) { return v - std::floor(v); };
  return {x0_m + 0.5 + i + 0.8 * (frac(0.6180339 * i + 0.4142135 * j) - 0.5),
          y0_m + 0.5 + j + 0.8 * (frac(0.7320508 * j + 0.2360679 * i) - 0.5)};
}

// One point of `f` (classification 2: the ground, 5: high vegetation).
void add_point(test::LasFixture& f, double x, double y, double z, int classification) {
  test::LasFixturePoint p;
  p.x = x;
  p.y = y;
  p.z = z;
  p.classification = classification;
  f.points.push_back(p);
}

// An empty LAS 1.4 cloud (point format 6) in UTM 33N, its CRS a WKT record.
test::LasFixture utm33_cloud() {
  test::LasFixture f;
  f.version_minor = 4;
  f.point_format = 6;
  f.wkt = utm33_wkt();
  f.offset[0] = x0_m;
  f.offset[1] = y0_m;
  return f;
}

// Ground points every metre over the plot, at ground_m + east_slope * (x - x0).
fs::path write_ground_cloud(const fs::path& dir, double east_slope) {
  test::LasFixture f = utm33_cloud();
  for (int j = 0; j < side_m; ++j)
    for (int i = 0; i < side_m; ++i) {
      const auto [x, y] = scattered(i, j);
      add_point(f, x, y, ground_m + east_slope * (x - x0_m), 2);
    }
  const fs::path file = dir / "ground.las";
  test::write_las(file, f);
  return file;
}

// A GLAS shot at nadir over the plot's centre from 100 km (a beam of sigma 11 m), on the
// cloud's ground.
nlohmann::json cloud_shot(const fs::path& cloud) {
  const auto [lon, lat] = ToLonLat()(x0_m + 0.5 * side_m, y0_m + 0.5 * side_m);
  return {{"seed", 7},
          {"sensor", {{"preset", "north2010"}}},
          {"simulation", {{"rays_per_shot", 10000}}},
          {"terrain", {{"point_cloud", true}, {"soil_reflectance", 0.15}}},
          {"canopy", {{"point_cloud", {{"file", cloud.string()}, {"voxel_size_m", 2.0}}}}},
          {"track",
           {{"type", "points"},
            {"points", {{{"lat_deg", lat}, {"lon_deg", lon}}}},
            {"altitude_m", 100000.0}}},
          {"output", {{"netcdf", false}, {"footprints", false}}}};
}

TEST(PointCloudTerrain, TheCloudsGroundWithinTwoCentimetres) {
  const test_support::ScratchDir dir("glaswave_cloud_terrain");
  const ToLonLat lon_lat;
  for (const double slope : {0.0, 0.1}) {
    const fs::path cloud = write_ground_cloud(dir.path(), slope);
    const Config config = parse_config(cloud_shot(cloud));
    const std::unique_ptr<Terrain> terrain = open_terrain(config);
    double worst_m = 0.0;
    // Inside the outer cells' centres, where the DEM's nodes are.
    for (int j = 0; j < 40; ++j)
      for (int i = 0; i < 40; ++i) {
        const double x = x0_m + 1.5 + (side_m - 3.0) * (i + 0.37) / 40.0;
        const double y = y0_m + 1.5 + (side_m - 3.0) * (j + 0.61) / 40.0;
        const auto [lon, lat] = lon_lat(x, y);
        const double expected_m = ground_m + slope * (x - x0_m);
        worst_m = std::max(worst_m, std::abs(terrain->height_m(lat, lon) - expected_m));
      }
    EXPECT_LT(worst_m, 0.02) << "slope " << slope;
    // Off the cloud there is no ground.
    const auto [lon, lat] = lon_lat(x0_m - 50.0, y0_m + 100.0);
    EXPECT_TRUE(std::isnan(terrain->height_m(lat, lon)));
  }
}

// PHYSICS.md section 1 at nadir: E = E_t T A_T rho f_fov / (pi R^2), R the altitude less the
// ground's height, the pulse centred on 2R/c.
TEST(PointCloudTerrain, AShotReturnsTheBareGroundClosedFormFromTheCloudsGround) {
  const test_support::ScratchDir dir("glaswave_cloud_terrain_shot");
  const fs::path cloud = write_ground_cloud(dir.path(), 0.0);
  const test_support::SimulatedTrack run = test_support::simulate_track(cloud_shot(cloud));
  const ShotRecord& shot = run.records.at(0);
  const double range_m = 100000.0 - ground_m;
  EXPECT_NEAR(shot.elev_m, ground_m, 0.02);
  EXPECT_NEAR(shot.range_m, range_m, 0.02);
  const double f_fov = 1.0 - std::exp(-0.0004 * 0.0004 / (8.0 * 0.00011 * 0.00011));
  const double energy_mJ[] = {32.0, 72.0}, transmission[] = {0.8, 0.9};
  for (int band = 0; band < 2; ++band) {
    const double expected_J = energy_mJ[band] * 1e-3 * transmission[band] * 0.709 * 0.15 * f_fov /
                              (std::numbers::pi * range_m * range_m);
    EXPECT_NEAR(shot.rx_energy_J[band] / expected_J, 1.0, 0.005) << "band " << band;
    EXPECT_EQ(shot.rx_energy_canopy_J[band], 0.0);
    const test_support::Moments m =
        test_support::waveform_moments(shot.rx_waveform_W[band], run.bin_time_ns);
    EXPECT_NEAR(m.mean_ns, 0.0, 0.1) << "band " << band;
  }
}

// Refused in one line naming /terrain/point_cloud, exit status 2, by check as by run.
TEST(PointCloudTerrain, RefusedWithoutACloudOrBesideAnotherGround) {
  const test_support::ScratchDir dir("glaswave_cloud_terrain_refused");
  const fs::path cloud = write_ground_cloud(dir.path(), 0.0);
  nlohmann::json crowns = cloud_shot(cloud);
  crowns["canopy"] = nlohmann::json::object();
  nlohmann::json beside = cloud_shot(cloud);
  beside["terrain"]["plane"] = {{"origin_lat_deg", 45.0}, {"origin_lon_deg", 15.0}};
  nlohmann::json voxels = cloud_shot(cloud);
  voxels["canopy"] = {{"voxels", {{"file", (dir.path() / "pad.nc").string()}}}};
  const std::pair<nlohmann::json, std::string> cases[] = {
      {crowns,
       "/terrain/point_cloud: is the ground of canopy.point_cloud's cloud, and the "
       "canopy has no point cloud"},
      {voxels, "/terrain/point_cloud: is the ground of canopy.point_cloud's cloud"},
      {beside, "/terrain/point_cloud: cannot be given beside terrain.plane"}};
  for (const auto& [document, message] : cases) {
    const fs::path config = dir.path() / "refused.json";
    std::ofstream(config) << document.dump();
    const std::string run = "run --quiet --out " + (dir / "out").string() + " ";
    for (const std::string& command : {std::string("check "), run}) {
      const test_support::CommandOutcome r = test_support::run_glaswave(command + config.string());
      EXPECT_EQ(r.status, 2) << r.output;
      EXPECT_EQ(r.output.find("glaswave: error: " + message), 0u) << r.output;
      EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    }
    EXPECT_FALSE(fs::exists(dir.path() / "out"));
  }
}

// ---- the same products however a run is spread ----------------------------------------------

// A cloud of the plot's middle 100 m (level ground) with nine crowns: within 6 m of a crown's axis
// every other pulse stops 7-12 m up.
fs::path write_forest_cloud(const fs::path& dir) {
  test::LasFixture f = utm33_cloud();
  for (int j = 50; j < 150; ++j)
    for (int i = 50; i < 150; ++i) {
      const auto [x, y] = scattered(i, j);
      const double u = std::remainder(x - x0_m - 0.5 * side_m, 15.0),
                   v = std::remainder(y - y0_m - 0.5 * side_m, 15.0);
      const bool crown = std::abs(x - x0_m - 0.5 * side_m) < 23 &&
                         std::abs(y - y0_m - 0.5 * side_m) < 23 && u * u + v * v < 36.0;
      if (crown && (i + j) % 2 == 0)
        add_point(f, x, y, ground_m + 7.0 + (i * 7 + j * 3) % 6, 5);
      else
        add_point(f, x, y, ground_m, 2);
    }
  const fs::path file = dir / "forest.las";
  test::write_las(file, f);
  return file;
}

// A facet tree: a square trunk of wood to 12 m and 300 leaf triangles of 0.3 m in a ball of 3 m
// about 9 m, their orientations from a fixed sequence.
void write_facet_tree(const fs::path& dir) {
  std::ofstream(dir / "tree.mtl") << "newmtl wood\nKd 0.3 0.2 0.1\nnewmtl leaf\nKd 0.1 0.5 0.1\n";
  std::ofstream obj(dir / "tree.obj");
  obj << "mtllib tree.mtl\nv -0.1 -0.1 0\nv 0.1 -0.1 0\nv 0.1 -0.1 12\nv -0.1 -0.1 12\n"
         "v -0.1 0.1 0\nv 0.1 0.1 0\nv 0.1 0.1 12\nv -0.1 0.1 12\n";
  double q = 0.5;
  const auto next = [&] { return q = std::fmod(q * 997.0 + 0.1234567, 1.0); };
  for (int leaf = 0; leaf < 300; ++leaf) {
    const double r = 3.0 * std::cbrt(next()), a = 2 * std::numbers::pi * next(), c = 2 * next() - 1,
                 s = std::sqrt(1 - c * c);
    const double cx = r * s * std::cos(a), cy = r * s * std::sin(a), cz = 9.0 + r * c;
    const double t = 2 * std::numbers::pi * next(), tilt = next();
    for (int k = 0; k < 3; ++k) {
      const double b = t + 2.0 * std::numbers::pi * k / 3.0;
      obj << "v " << cx + 0.17 * std::cos(b) << " " << cy + 0.17 * std::sin(b) * tilt << " "
          << cz + 0.17 * std::sin(b) * (1 - tilt) << "\n";
    }
  }
  obj << "usemtl wood\nf 1 2 3\nf 1 3 4\nf 5 6 7\nf 5 7 8\nf 1 5 8\nf 1 8 4\nf 2 6 7\nf 2 7 3\n"
         "usemtl leaf\n";
  for (int leaf = 0; leaf < 300; ++leaf)
    obj << "f " << 9 + 3 * leaf << " " << 10 + 3 * leaf << " " << 11 + 3 * leaf << "\n";
  std::ofstream trees(dir / "trees.csv");
  trees << "x,y,model,rotation_deg,scale\n";
  for (int k = 0; k < 9; ++k)
    trees << (k % 3 - 1) * 15.0 << "," << (k / 3 - 1) * 15.0 << ",tree," << 40 * k << ","
          << 0.8 + 0.05 * k << "\n";
}

// 24 GEDI shots 2 m apart northward across the plot's centre, 200 rays to order 3, over one of
// the three sources made in `dir`.
fs::path source_config(const fs::path& dir, const std::string& source) {
  const auto [lon, lat] = ToLonLat()(x0_m + 0.5 * side_m, y0_m + 0.5 * side_m);
  const auto [lon0, lat0] = ToLonLat()(x0_m + 0.5 * side_m, y0_m + 0.5 * side_m - 24.0);
  nlohmann::json plane = {
      {"origin_lat_deg", lat}, {"origin_lon_deg", lon}, {"elevation_m", ground_m}};
  nlohmann::json config = {{"seed", 11},
                           {"sensor", {{"preset", "gedi"}}},
                           {"simulation", {{"rays_per_shot", 200}, {"max_order", 3}}},
                           {"terrain", {{"plane", plane}}},
                           {"track",
                            {{"type", "pass"},
                             {"start_lat_deg", lat0},
                             {"start_lon_deg", lon0},
                             {"heading_deg", 0.0},
                             {"shots", 24},
                             {"spacing_m", 2.0},
                             {"altitude_m", 420000.0}}},
                           {"output", {{"per_order", true}}}};
  const nlohmann::json leaves = {{"leaf_reflectance", 0.45}, {"leaf_transmittance", 0.45}};
  if (source == "point_cloud") {
    config["terrain"] = {{"point_cloud", true}};
    config["canopy"]["point_cloud"] = {{"file", (dir / "forest.las").string()},
                                       {"voxel_size_m", 2.0}};
    config["canopy"]["point_cloud"].update(leaves);
  } else if (source == "voxels") {
    config["canopy"]["voxels"] = {{"file", (dir / "pad.nc").string()}};
    config["canopy"]["voxels"].update(leaves);
  } else {
    config["canopy"]["facets"] = {{"trees_file", (dir / "trees.csv").string()},
                                  {"models", {{"tree", (dir / "tree.obj").string()}}},
                                  {"materials",
                                   {{"leaf", {{"reflectance", 0.45}, {"transmittance", 0.45}}},
                                    {"wood", {{"reflectance", 0.3}}}}}};
  }
  const fs::path file = dir / (source + ".json");
  std::ofstream(file) << config.dump(2);
  return file;
}

// The run's received energy whose last scattering was on vegetation, over every shot and band.
double canopy_energy_J(const fs::path& shots_nc) {
  int nc = -1, var = -1;
  if (nc_open(shots_nc.c_str(), NC_NOWRITE, &nc) != NC_NOERR) return 0.0;
  std::size_t shots = 0, bands = 0;
  int dims[2];
  nc_inq_varid(nc, "rx_energy_canopy", &var);
  nc_inq_vardimid(nc, var, dims);
  nc_inq_dimlen(nc, dims[0], &shots);
  nc_inq_dimlen(nc, dims[1], &bands);
  std::vector<double> energy(shots * bands);
  nc_get_var_double(nc, var, energy.data());
  nc_close(nc);
  double sum = 0.0;
  for (const double e : energy) sum += e;
  return sum;
}

class VegetationRuns : public ::testing::TestWithParam<std::string> {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test_support::ScratchDir("glaswave_vegetation_runs");
    write_forest_cloud(dir_->path());
    write_facet_tree(dir_->path());
    const test_support::CommandOutcome voxelized = test_support::run_glaswave(
        "voxelize " + (dir_->path() / "forest.las").string() + " --out " +
        (dir_->path() / "pad.nc").string() + " --voxel-size-m 2");
    ASSERT_EQ(voxelized.status, 0) << voxelized.output;
  }
  static void TearDownTestSuite() { delete dir_; }
  static test_support::ScratchDir* dir_;
};
test_support::ScratchDir* VegetationRuns::dir_ = nullptr;

TEST_P(VegetationRuns, TheSameProductsForAnyThreadsSplitProcessesAndResume) {
  const fs::path dir = dir_->path() / GetParam();
  fs::create_directories(dir);
  const std::string config = source_config(dir_->path(), GetParam()).string();
  const auto run = [&](const std::string& name, const std::string& extra) {
    const test_support::CommandOutcome r = test_support::run_glaswave(
        "run " + config + " --quiet --out " + (dir / name).string() + " " + extra);
    EXPECT_EQ(r.status, 0) << name << ": " << r.output;
  };
  run("one", "--threads 1");
  run("two", "--threads 2");
  run("first", "--threads 2 --shots 0:12");
  run("rest", "--threads 1 --shots 12:24");
  // The shots see the vegetation: its returns are in the products compared.
  EXPECT_GT(canopy_energy_J(dir / "one" / "shots.nc"), 0.0);
  test_support::expect_same_products(dir / "one", dir / "two");
  test_support::expect_same_split(dir / "one", {dir / "first", dir / "rest"});

  const test_support::CommandOutcome mpi = test_support::run_mpi(
      2, "run " + config + " --quiet --threads 1 --out " + (dir / "mpi").string());
  ASSERT_EQ(mpi.status, 0) << mpi.output;
  test_support::expect_same_products(dir / "one", dir / "mpi");

  // Killed after its first batch of 8 shots on one thread, then resumed.
  const std::string killed =
      "run " + config + " --quiet --threads 1 --out " + (dir / "killed").string();
  ASSERT_TRUE(test_support::kill_when(test_support::start_glaswave(killed),
                                      dir / "killed" / "glaswave.journal", 17))
      << "the run ended first";
  const test_support::CommandOutcome resumed = test_support::run_glaswave(killed + " --resume");
  ASSERT_EQ(resumed.status, 0) << resumed.output;
  test_support::expect_same_products(dir / "one", dir / "killed");
}

INSTANTIATE_TEST_SUITE_P(Sources, VegetationRuns,
                         ::testing::Values("voxels", "point_cloud", "facets"));

}  // namespace
}  // namespace glaswave
