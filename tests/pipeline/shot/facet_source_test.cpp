// Facet trees through the whole shot (files read, trees placed on the terrain, Embree instances,
// transport, receiver, truth), against numbers known without the code: a Lambertian facet plane
// is PHYSICS.md section 1's bare ground; and the files it refuses, each in one line naming the
// file.
#include "pipeline/shot/facet_source.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>

#include "core/error.hpp"
#include "pipeline/scene/scene.hpp"
#include "pipeline/scene/vegetation.hpp"
#include "tests/pipeline/shot/shot_test_support.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

using namespace glaswave::testing;

void write(const std::filesystem::path& file, const std::string& text) {
  std::ofstream(file) << text;
}

// A square plate 800 m across, 1 m above the model's origin, of material `material` (two
// triangles), as OBJ with its MTL.
void write_plate(const std::filesystem::path& folder, const std::string& material) {
  write(folder / "plate.mtl", "newmtl " + material + "\nKd 0.5 0.5 0.5\n");
  write(folder / "plate.obj",
        "mtllib plate.mtl\nv -400 -400 1\nv 400 -400 1\nv 400 400 1\nv -400 400 1\n"
        "usemtl " +
            material + "\nf 1 2 3\nf 1 3 4\n");
}

VegetationSettings plate_settings(const std::filesystem::path& folder) {
  write(folder / "trees.csv", "x,y,model,rotation_deg,scale\n0,0,plate,30,1\n");
  VegetationSettings settings;
  settings.plane = PlaneSettings{kLat0, kLon0, 0.0, 0.0, 0.0};
  settings.canopy.kind = "facets";
  settings.canopy.facet_trees_file = (folder / "trees.csv").string();
  settings.canopy.facet_models = {{"plate", (folder / "plate.obj").string()}};
  settings.canopy.facet_materials = {{"wood", {0.4}, {0.0}, false}, {"leaf", {0.45}, {0.45}, true}};
  return settings;
}

// PHYSICS.md section 1: E_rec = E_t T A_T rho cos(alpha) f_fov / (pi R^2), here with the plate's
// rho 0.4 over a black ground at nadir. Every ray scores the plate's reflectance toward the
// detector (nothing lies above it to scatter back), so the energy is exact to round-off; the
// 1 m the plate stands above the ground changes R by 2e-6. To 0.5 %, as the ground's own test.
// Its truth: cover 1, height 1 m, and one square metre of plate per square metre of ground
// under the beam (PAI 1).
TEST(FacetSource, LambertianFacetPlaneIsTheBareGroundClosedForm) {
  test_support::ScratchDir dir;
  write_plate(dir.path(), "wood");
  const std::unique_ptr<Terrain> terrain = plane_terrain(0.0);
  const ShotSettings settings = shot_settings(0.0, 4000);
  const ShotSimulator simulator(settings, *terrain,
                                make_vegetation_source(plate_settings(dir.path())),
                                make_receiver(receiver_settings(settings, "waveform")));
  const Footprint footprint = nadir_footprint(*terrain);
  const ShotRecord record = simulator.simulate(footprint);
  ASSERT_EQ(record.quality_flag, quality_good);
  const double f_fov = 1.0 - std::exp(-0.0004 * 0.0004 / (8.0 * 0.00011 * 0.00011));
  const double closed_form =
      1e-3 * 0.709 * 0.4 * f_fov / (std::numbers::pi * footprint.range_m * footprint.range_m);
  RecordProperty("ratio", std::to_string(record.rx_energy_J[0] / closed_form));
  EXPECT_NEAR(record.rx_energy_J[0] / closed_form, 1.0, 0.005);
  EXPECT_EQ(record.rx_energy_ground_J[0], 0.0);
  EXPECT_NEAR(record.cover_true, 1.0, 1e-12);
  EXPECT_NEAR(record.canopy_height_true_m, 1.0, 0.01);
  EXPECT_NEAR(record.pai_true, 1.0, 0.002);
}

// A leaf plate (bi-Lambertian, rho 0.45, tau 0.45) 1 m over a white ground, covering the beam:
// what each order returns follows from the two sides alone. Order 1 is the plate's reflectance,
// 0.45; order 2 ends on the ground, which the laser cannot light through the plate: 0; order 3
// is the light the plate transmits down, the ground reflects and the plate transmits up again,
// tau^2 rho_s = 0.2025 (the plate is 400 m wide, the light spreads a few metres); order 4 ends
// on the ground again: 0. No return's first element is the ground. Order 1 to 0.5 % (every ray
// scores 0.45), order 3 to 4 % (about 4 standard errors at 8000 rays).
TEST(FacetSource, LeafFacetsReflectToTheirSideAndTransmitToTheOther) {
  test_support::ScratchDir dir;
  write_plate(dir.path(), "leaf");
  const std::unique_ptr<Terrain> terrain = plane_terrain(1.0);
  ShotSettings settings = shot_settings(1.0, 8000);
  settings.transport.per_order = true;
  const ShotSimulator simulator(settings, *terrain,
                                make_vegetation_source(plate_settings(dir.path())),
                                make_receiver(receiver_settings(settings, "waveform")));
  const Footprint footprint = nadir_footprint(*terrain);
  const ShotRecord record = simulator.simulate(footprint);
  const double f_fov = 1.0 - std::exp(-0.0004 * 0.0004 / (8.0 * 0.00011 * 0.00011));
  const double unit_J =
      1e-3 * 0.709 * f_fov / (std::numbers::pi * footprint.range_m * footprint.range_m);
  ASSERT_EQ(record.rx_waveform_order_W.size(), 1u);
  ASSERT_EQ(record.rx_waveform_order_W[0].size(), 4u);
  std::vector<double> order(4, 0.0);
  for (int k = 0; k < 4; ++k)
    for (double power_W : record.rx_waveform_order_W[0][k]) order[k] += power_W * 1e-9 / unit_J;
  RecordProperty("order1", std::to_string(order[0]));
  RecordProperty("order3", std::to_string(order[2]));
  EXPECT_NEAR(order[0], 0.45, 0.005 * 0.45);
  EXPECT_EQ(order[1], 0.0);
  EXPECT_NEAR(order[2], 0.2025, 0.04 * 0.2025);
  EXPECT_EQ(order[3], 0.0);
  EXPECT_EQ(record.rx_energy_ground_J[0], 0.0);
}

// The trees file in its three forms puts a tree in the same place: x,y metres on the plane,
// lon,lat degrees, and a GeoJSON point in UTM zone 32N (the footprint at 45 N 7 E is at
// x 342 369.36, y 4 984 896.17 there, by gdaltransform), each turned and scaled as given, its
// foot on the terrain (a plane at 0 m: the frame's origin is the footprint's ground).
TEST(FacetSource, TreesFromCsvAndAnyOgrLayerStandWhereTheySay) {
  test_support::ScratchDir dir;
  write_plate(dir.path(), "wood");
  VegetationSettings settings = plate_settings(dir.path());
  const std::unique_ptr<Terrain> terrain = plane_terrain(0.3);
  const LocalFrame frame({kLat0, kLon0, 0.0});
  auto one_tree = [&](const std::string& file) {
    settings.canopy.facet_trees_file = (dir.path() / file).string();
    const RegionVegetation grown =
        make_vegetation_source(settings)->grow({*terrain, frame, 50.0, {}, 1});
    EXPECT_EQ(grown.geometry.facets.size(), 1u) << file;
    EXPECT_EQ(grown.geometry.leaf_materials, (std::vector<char>{0, 1})) << file;
    return grown.geometry.facets.at(0);
  };
  write(dir.path() / "metres.csv", "x,y,model,rotation_deg,scale\n3,-4,plate,90,2\n");
  const FacetInstance metres = one_tree("metres.csv");
  EXPECT_NEAR(metres.foot_m[0], 3.0, 1e-3);
  EXPECT_NEAR(metres.foot_m[1], -4.0, 1e-3);
  EXPECT_NEAR(metres.foot_m[2], 0.0, 1e-3);
  EXPECT_NEAR(metres.rotation_rad, std::numbers::pi / 2, 1e-12);
  EXPECT_EQ(metres.scale, 2.0);
  write(dir.path() / "degrees.csv", "lon,lat,model,rotation_deg,scale\n7.0,45.0,plate,0,1\n");
  const FacetInstance degrees = one_tree("degrees.csv");
  EXPECT_NEAR(std::hypot(degrees.foot_m[0], degrees.foot_m[1]), 0.0, 1e-3);
  // UTM 32N of (45 N, 7 E) by gdaltransform: 342369.36, 4984896.17.
  write(dir.path() / "utm.geojson",
        R"({"type": "FeatureCollection",
            "crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::32632"}},
            "features": [{"type": "Feature",
                          "properties": {"model": "plate", "rotation_deg": 45.0, "scale": 1.5},
                          "geometry": {"type": "Point", "coordinates": [342369.36, 4984896.17]}}]})");
  const FacetInstance utm = one_tree("utm.geojson");
  EXPECT_NEAR(utm.foot_m[0], 0.0, 0.01);
  EXPECT_NEAR(utm.foot_m[1], 0.0, 0.01);
  EXPECT_NEAR(utm.rotation_rad, std::numbers::pi / 4, 1e-12);
  EXPECT_EQ(utm.scale, 1.5);
}

// The truth's plant area of one small plate, turned and scaled, away from the beam's centre:
// a 0.5 m square centred 2 m east and 10 m north of its model's origin (0.25 m^2), a tree at
// (3, -4) turned 90 degrees (north to east) at scale 2, puts 1 m^2 of plate at (23, -8). Under
// a beam of RMS radius 10 m centred at (13, 1), the PAI is 1 m^2 exp(-181 / 200) /
// (2 pi 10^2) = 6.44e-4; the plate turned the other way (at -17, 0) or not at all (at 7, 16)
// would give 1.8e-5 or 4.3e-4. To 0.5 %: the area is gathered at 0.25 m cells' centres, which
// the plate's own centre lies between.
TEST(FacetSource, TruthWeighsATurnedScaledTreeWhereItStands) {
  test_support::ScratchDir dir;
  write(dir.path() / "plate.mtl", "newmtl leaf\n");
  write(dir.path() / "plate.obj",
        "mtllib plate.mtl\nv 1.75 9.75 1\nv 2.25 9.75 1\nv 2.25 10.25 1\nv 1.75 10.25 1\n"
        "usemtl leaf\nf 1 2 3\nf 1 3 4\n");
  VegetationSettings settings = plate_settings(dir.path());
  write(dir.path() / "trees.csv", "x,y,model,rotation_deg,scale\n3,-4,plate,90,2\n");
  const std::unique_ptr<VegetationSource> source = make_vegetation_source(settings);
  const std::unique_ptr<Terrain> terrain = plane_terrain(0.0);
  const LocalFrame frame({kLat0, kLon0, 0.0});
  const RegionVegetation grown = source->grow({*terrain, frame, 50.0, {}, 1});
  ASSERT_EQ(grown.geometry.facets.size(), 1u);
  const RayDevice device;
  const Scene scene(device, GroundMesh{}, grown.geometry);
  const double sigma_m = 10.0;
  const VegetationTruth truth = source->truth(scene, {13.0, 1.0, sigma_m}, {});
  const double expected = std::exp(-0.905) / (2.0 * std::numbers::pi * sigma_m * sigma_m);
  EXPECT_NEAR(truth.pai / expected, 1.0, 0.005) << truth.pai;
  // An opaque facet leaves no gap where it covers.
  EXPECT_GT(truth.cover, 0.0);
  EXPECT_DOUBLE_EQ(truth.gap_probability, 1.0 - truth.cover);
}

// A floating instance (the trees file's z_m): one disc leaf model, a horizontal disc of radius
// 300 m (wider than the beam) 0.5 m above its origin, placed at z_m 0 and at z_m 10; at order 1
// over black ground the waveform is the pulse reflected by the disc, so that the second arrives
// earlier by 2 z / c = 2 * 10 / 299 792 458 m/s = 66.713 ns: its centroid within half a bin of
// 0.1 ns (the transport tallies each return's time to its bin; with 1 ns bins the shift comes out
// 67 ns; both waveforms are the same Gaussian shifted, each window placed by the scene's top),
// its energy the same (the range changes R^2 by 3e-5), and the truth's canopy height 0.5 and
// 10.5 m.
TEST(FacetSource, AFloatingInstanceReturnsEarlierByTwiceItsHeightOverC) {
  test_support::ScratchDir dir;
  write(dir.path() / "disc.def", "# radius x y z nx ny nz\n300 0 0 0.5 0 0 1\n");
  VegetationSettings vegetation = plate_settings(dir.path());
  vegetation.canopy.facet_models = {{"disc", (dir.path() / "disc.def").string()}};
  const std::unique_ptr<Terrain> terrain = plane_terrain(0.0);
  ShotSettings settings = shot_settings(0.0, 2000);
  settings.transport.max_order = 1;
  settings.lidar.bin_ns = 0.1;  // the transport tallies a return's time to its bin
  settings.lidar.bins = 5440;
  const Footprint footprint = nadir_footprint(*terrain);
  auto shot = [&](double z_m) {
    write(dir.path() / "trees.csv",
          "x,y,model,rotation_deg,scale,z_m\n0,0,disc,0,1," + std::to_string(z_m) + "\n");
    const ShotSimulator simulator(settings, *terrain, make_vegetation_source(vegetation),
                                  make_receiver(receiver_settings(settings, "waveform")));
    return simulator.simulate(footprint);
  };
  // The arrival time of a waveform's centroid after a fixed instant (the return from elevation
  // 0): its bin's time in the window, less the window's start, 2 elev_bin0_m / c before it.
  auto arrival_ns = [](const ShotRecord& record) {
    const std::vector<double>& power_W = record.rx_waveform_W[0];
    double sum = 0.0, moment = 0.0;
    for (std::size_t b = 0; b < power_W.size(); ++b) {
      sum += power_W[b];
      moment += power_W[b] * static_cast<double>(b);
    }
    return moment / sum * 0.1 - 2.0 * record.elev_bin0_m / 299792458.0 * 1e9;  // bins of 0.1 ns
  };
  const ShotRecord standing = shot(0.0), floating = shot(10.0);
  ASSERT_EQ(standing.quality_flag, quality_good);
  ASSERT_EQ(floating.quality_flag, quality_good);
  const double shift_ns = arrival_ns(standing) - arrival_ns(floating);
  RecordProperty("shift_ns", std::to_string(shift_ns));
  EXPECT_NEAR(shift_ns, 2.0 * 10.0 / 299792458.0 * 1e9, 0.05);
  EXPECT_NEAR(floating.rx_energy_J[0] / standing.rx_energy_J[0], 1.0, 1e-3);
  EXPECT_EQ(standing.rx_energy_ground_J[0], 0.0);
  EXPECT_NEAR(standing.canopy_height_true_m, 0.5, 0.01);
  EXPECT_NEAR(floating.canopy_height_true_m, 10.5, 0.01);
}

std::string refusal(const VegetationSettings& settings) {
  try {
    make_vegetation_source(settings);
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::input);
    return e.what();
  }
  ADD_FAILURE() << "not refused";
  return "";
}

// Each refused with one line that names the file (and what is wrong), never a crash.
TEST(FacetSource, BadFilesAreRefusedNamingTheFile) {
  test_support::ScratchDir dir;
  write_plate(dir.path(), "bark");
  VegetationSettings settings = plate_settings(dir.path());
  std::string message = refusal(settings);
  EXPECT_NE(message.find("plate.obj"), std::string::npos) << message;
  EXPECT_NE(message.find("\"bark\""), std::string::npos) << message;

  write_plate(dir.path(), "wood");
  write(dir.path() / "plate.obj", "v 0 0 0\nv 1 0 0\nf 1 2 9\n");  // a face past the vertices
  message = refusal(settings);
  EXPECT_NE(message.find("plate.obj"), std::string::npos) << message;
  write(dir.path() / "plate.obj", std::string(1000, '\x07'));
  message = refusal(settings);
  EXPECT_NE(message.find("plate.obj"), std::string::npos) << message;
  write(dir.path() / "plate.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n");  // no area
  message = refusal(settings);
  EXPECT_NE(message.find("no triangle of any area"), std::string::npos) << message;
  write(dir.path() / "plate.obj", "v 0 0 0\nv 1 0 0\nv 0 5000 0\nf 1 2 3\n");  // 5 km
  message = refusal(settings);
  EXPECT_NE(message.find("beyond 1 km"), std::string::npos) << message;

  write_plate(dir.path(), "wood");
  write(dir.path() / "trees.csv", "x,y,model,rotation_deg,scale\n0,0,oak,0,1\n");
  settings.canopy.facet_trees_file = (dir.path() / "trees.csv").string();
  message = refusal(settings);
  EXPECT_NE(message.find("trees.csv:2"), std::string::npos) << message;
  EXPECT_NE(message.find("oak"), std::string::npos) << message;
  write(dir.path() / "trees.csv", "x,y,model,rotation_deg,scale\n0,0,plate,0,-1\n");
  message = refusal(settings);
  EXPECT_NE(message.find("scale"), std::string::npos) << message;
  write(dir.path() / "trees.csv", "x,y,model,scale\n0,0,plate,1\n");
  message = refusal(settings);
  EXPECT_NE(message.find("header"), std::string::npos) << message;
  write(dir.path() / "trees.gpkg", "not a geopackage");
  settings.canopy.facet_trees_file = (dir.path() / "trees.gpkg").string();
  message = refusal(settings);
  EXPECT_NE(message.find("trees.gpkg"), std::string::npos) << message;
  for (const std::string& m : {message}) EXPECT_EQ(m.find('\n'), std::string::npos) << m;

  // A disc leaf model: a malformed line named by file and line; discs of a material that
  // canopy.facets.materials does not give, named by the key.
  settings = plate_settings(dir.path());
  settings.canopy.facet_models = {{"plate", (dir.path() / "plate.def").string()}};
  write(dir.path() / "plate.def", "0.1 0 0 1 0 0 1\n0.1 0 0 1 0 0\n");
  message = refusal(settings);
  EXPECT_NE(message.find("plate.def:2:"), std::string::npos) << message;
  write(dir.path() / "plate.def", "0.1 0 0 1 0 0 1\n");
  settings.canopy.facet_disc_material = "needle";
  message = refusal(settings);
  EXPECT_NE(message.find("\"needle\" (canopy.facets.disc_material)"), std::string::npos) << message;
}

}  // namespace
}  // namespace glaswave
