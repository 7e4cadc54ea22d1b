// End to end: the built glaswave command run as a user runs it, its products read back
// with netCDF-C and GDAL's OGR, and its errors checked against PRODUCT.md sections 2 and 5.
#include <gdal_priv.h>
#include <gtest/gtest.h>
#include <netcdf.h>
#include <ogrsf_frmts.h>
#include <sys/wait.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "tests/pipeline/engine/engine_test_support.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

namespace fs = std::filesystem;
using namespace test_support;

class Cli : public ::testing::Test {
 protected:
  // A short pass over a sloped plane.
  std::string write_config(const nlohmann::json& changes = nlohmann::json::object()) {
    nlohmann::json config = {
        {"seed", 3},
        {"sensor", {{"preset", "glas"}}},
        {"simulation", {{"rays_per_shot", 3000}}},
        {"terrain",
         {{"plane",
           {{"origin_lat_deg", 46.0},
            {"origin_lon_deg", 8.0},
            {"elevation_m", 900.0},
            {"slope_deg", 8.0},
            {"aspect_deg", 200.0}}}}},
        {"canopy", nullptr},
        {"track",
         {{"type", "pass"},
          {"start_lat_deg", 46.0},
          {"start_lon_deg", 8.0},
          {"heading_deg", 350.0},
          {"shots", 5},
          {"spacing_m", 172.0}}},
    };
    config.merge_patch(changes);
    const fs::path file = dir_ / "track.json";
    std::ofstream(file) << config.dump(2);
    return file.string();
  }

  ScratchDir dir_{"glaswave_cli"};
};

// rx_waveform of shots.nc, flattened.
std::vector<float> read_waveforms(const fs::path& file, std::size_t* shots = nullptr) {
  int nc = -1, var = -1, dims[3];
  EXPECT_EQ(nc_open(file.c_str(), NC_NOWRITE, &nc), NC_NOERR) << file;
  EXPECT_EQ(nc_inq_varid(nc, "rx_waveform", &var), NC_NOERR);
  EXPECT_EQ(nc_inq_vardimid(nc, var, dims), NC_NOERR);
  std::size_t size = 1, length = 0;
  for (int dim : dims) {
    nc_inq_dimlen(nc, dim, &length);
    size *= length;
  }
  if (shots) nc_inq_dimlen(nc, dims[0], shots);
  std::vector<float> values(size);
  EXPECT_EQ(nc_get_var_float(nc, var, values.data()), NC_NOERR);
  nc_close(nc);
  return values;
}

TEST_F(Cli, RunWritesProductsThatReadBack) {
  const std::string config = write_config();
  const CommandOutcome run =
      run_glaswave("run " + config + " --out " + (dir_ / "out").string() + " --quiet");
  ASSERT_EQ(run.status, 0) << run.output;
  // The summary line: shots, seconds, shots/s, ray queries/s.
  EXPECT_NE(run.output.find("5 shots in"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("shots/s"), std::string::npos);
  EXPECT_NE(run.output.find("ray queries/s"), std::string::npos);

  std::size_t shots = 0;
  const std::vector<float> waveforms = read_waveforms(dir_ / "out" / "shots.nc", &shots);
  EXPECT_EQ(shots, 5u);
  float peak = 0;
  for (float value : waveforms) peak = std::max(peak, value);
  EXPECT_GT(peak, 0.0f);

  int nc = -1, var = -1;
  ASSERT_EQ(nc_open((dir_ / "out" / "shots.nc").c_str(), NC_NOWRITE, &nc), NC_NOERR);
  char feature_type[64] = {};
  EXPECT_EQ(nc_get_att_text(nc, NC_GLOBAL, "featureType", feature_type), NC_NOERR);
  EXPECT_STREQ(feature_type, "trajectory");
  std::size_t history_length = 0;
  EXPECT_EQ(nc_inq_attlen(nc, NC_GLOBAL, "history", &history_length), NC_NOERR);
  std::string history(history_length, '\0');
  nc_get_att_text(nc, NC_GLOBAL, "history", history.data());
  EXPECT_NE(history.find("run " + config), std::string::npos) << history;
  // The slope of the plane and the reflectance of eq. (1): rho_s cos(S) f_fov, f_fov ~ 1 here.
  double slope[5], reflectance[10], range_m[5];
  ASSERT_EQ(nc_inq_varid(nc, "range_m", &var), NC_NOERR);
  nc_get_var_double(nc, var, range_m);
  ASSERT_EQ(nc_inq_varid(nc, "slope_deg", &var), NC_NOERR);
  nc_get_var_double(nc, var, slope);
  ASSERT_EQ(nc_inq_varid(nc, "reflectance", &var), NC_NOERR);
  nc_get_var_double(nc, var, reflectance);
  nc_close(nc);
  const double f_fov = 1.0 - std::exp(-0.0004 * 0.0004 / (8.0 * 0.0000292 * 0.0000292));
  for (int shot = 0; shot < 5; ++shot) {
    EXPECT_NEAR(slope[shot], 8.0, 0.01);
    EXPECT_NEAR(reflectance[2 * shot] / (0.15 * std::cos(8.0 * M_PI / 180.0) * f_fov), 1.0, 0.01);
  }

  GDALAllRegister();
  GDALDataset* geojson = static_cast<GDALDataset*>(GDALOpenEx(
      (dir_ / "out" / "footprints.geojson").c_str(), GDAL_OF_VECTOR, nullptr, nullptr, nullptr));
  ASSERT_NE(geojson, nullptr);
  OGRLayer* layer = geojson->GetLayer(0);
  EXPECT_EQ(layer->GetFeatureCount(), 5);
  OGRFeature* feature = layer->GetNextFeature();
  ASSERT_NE(feature, nullptr);
  ASSERT_EQ(wkbFlatten(feature->GetGeometryRef()->getGeometryType()), wkbPolygon);
  // The footprint polygon traces the beam's 1/e^2 contour, 2 sigma = 5.84e-5 rad from the axis
  // (glas preset), at nadir: seen from above, 36 points on a circle of radius R tan(2 sigma),
  // about 35 m, whatever the slope. Their polygon's area is 18 r^2 sin(10 deg); the ring is
  // measured in metres with the series for a degree of latitude and longitude at 46 N (1e-5),
  // and its coordinates are rounded in the file (cm): within 0.2 %.
  const OGRLinearRing* ring = feature->GetGeometryRef()->toPolygon()->getExteriorRing();
  const double phi = 46.0 * M_PI / 180.0;
  const double m_lat = 111132.954 - 559.822 * std::cos(2 * phi) + 1.175 * std::cos(4 * phi),
               m_lon = 111412.84 * std::cos(phi) - 93.5 * std::cos(3 * phi);
  double twice_area_m2 = 0.0;
  for (int i = 0; i + 1 < ring->getNumPoints(); ++i)
    twice_area_m2 += (ring->getX(i) * m_lon) * (ring->getY(i + 1) * m_lat) -
                     (ring->getX(i + 1) * m_lon) * (ring->getY(i) * m_lat);
  const double radius_m = range_m[0] * std::tan(2.0 * 0.0000292);
  EXPECT_EQ(ring->getNumPoints(), 37);  // closed
  EXPECT_NEAR(0.5 * twice_area_m2 / (18.0 * radius_m * radius_m * std::sin(M_PI / 18.0)), 1.0,
              2e-3);
  OGRFeature::DestroyFeature(feature);
  GDALClose(geojson);
}

// A pass across the antimeridian, its first footprint straddling the line (RFC 7946 sections
// 3.1.6 and 3.1.9): that footprint is a MultiPolygon of two parts, one each side, and every
// exterior ring of every footprint is counter-clockwise with lon/lat within +-180 and +-90. The
// orientation is the sign of the ring's area computed here from its points.
TEST_F(Cli, AntimeridianTrackFootprintsAreCutCounterClockwiseWithinRange) {
  const std::string config =
      write_config({{"simulation", {{"rays_per_shot", 100}}},
                    {"terrain", {{"plane", {{"origin_lon_deg", 179.9999}}}}},
                    {"track", {{"start_lon_deg", 179.9999}, {"heading_deg", 90.0}, {"shots", 4}}}});
  const CommandOutcome run =
      run_glaswave("run " + config + " --quiet --out " + (dir_ / "out").string());
  ASSERT_EQ(run.status, 0) << run.output;
  GDALAllRegister();
  GDALDatasetUniquePtr dataset(GDALDataset::FromHandle(
      GDALOpenEx((dir_ / "out" / "footprints.geojson").c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY,
                 nullptr, nullptr, nullptr)));
  ASSERT_TRUE(dataset);
  int features = 0, multipolygons = 0, rings = 0;
  for (auto& feature : *dataset->GetLayer(0)) {
    ++features;
    const OGRGeometry* geometry = feature->GetGeometryRef();
    ASSERT_NE(geometry, nullptr);
    std::vector<const OGRPolygon*> parts;
    if (wkbFlatten(geometry->getGeometryType()) == wkbMultiPolygon) {
      ++multipolygons;
      for (const OGRPolygon* part : *geometry->toMultiPolygon()) parts.push_back(part);
    } else {
      ASSERT_EQ(wkbFlatten(geometry->getGeometryType()), wkbPolygon);
      parts.push_back(geometry->toPolygon());
    }
    for (const OGRPolygon* part : parts) {
      ++rings;
      const OGRLinearRing* ring = part->getExteriorRing();
      double twice_area = 0.0;
      for (int i = 0; i + 1 < ring->getNumPoints(); ++i) {
        twice_area += ring->getX(i) * ring->getY(i + 1) - ring->getX(i + 1) * ring->getY(i);
        EXPECT_LE(std::abs(ring->getX(i)), 180.0);
        EXPECT_LE(std::abs(ring->getY(i)), 90.0);
      }
      EXPECT_GT(twice_area, 0.0) << "shot " << features - 1;
    }
  }
  EXPECT_EQ(features, 4);
  EXPECT_EQ(multipolygons, 1);
  EXPECT_EQ(rings, 5);
}

// In a forest with rough ground and every scattering order, the hardest case for determinism.
TEST_F(Cli, ResultsDoNotDependOnThreadsOrShotSplits) {
  const std::string config =
      write_config({{"canopy", {{"cover", 0.6}}},
                    {"terrain", {{"roughness", {{"rms_m", 0.3}, {"correlation_m", 3.0}}}}},
                    {"output", {{"per_order", true}}}});
  ASSERT_EQ(run_glaswave("run " + config + " --quiet --threads 1 --out " + (dir_ / "one").string())
                .status,
            0);
  ASSERT_EQ(run_glaswave("run " + config + " --quiet --threads 2 --out " + (dir_ / "two").string())
                .status,
            0);
  ASSERT_EQ(
      run_glaswave("run " + config + " --quiet --shots 0:2 --out " + (dir_ / "a").string()).status,
      0);
  ASSERT_EQ(
      run_glaswave("run " + config + " --quiet --shots 2:5 --out " + (dir_ / "b").string()).status,
      0);
  const std::vector<float> one = read_waveforms(dir_ / "one" / "shots.nc");
  EXPECT_EQ(one, read_waveforms(dir_ / "two" / "shots.nc"));
  std::vector<float> split = read_waveforms(dir_ / "a" / "shots.nc");
  const std::vector<float> rest = read_waveforms(dir_ / "b" / "shots.nc");
  split.insert(split.end(), rest.begin(), rest.end());
  EXPECT_EQ(one, split);
  // Another seed is another sample.
  ASSERT_EQ(
      run_glaswave("run " + config + " --quiet --seed 4 --out " + (dir_ / "seed4").string()).status,
      0);
  EXPECT_NE(one, read_waveforms(dir_ / "seed4" / "shots.nc"));
}

// --threads asks for more threads than the cores the process may run on (taskset narrows them,
// as batch systems and mpirun do): it runs on those, and says so rather than silently.
TEST_F(Cli, ThreadsBeyondTheProcessesCoresAreNamed) {
  const unsigned cores = std::thread::hardware_concurrency();
  if (cores < 2) GTEST_SKIP() << "one core: nothing to narrow";
  if (std::system("command -v taskset >/dev/null 2>&1") != 0) GTEST_FAIL() << "no taskset";
  const std::string config = write_config({{"simulation", {{"rays_per_shot", 200}}}});
  const CommandOutcome narrowed =
      run_command("taskset -c 0 " + std::string(GLASWAVE_BINARY) + " run " + config +
                  " --quiet --threads 2 --out " + (dir_ / "narrowed").string() + " 2>&1");
  ASSERT_EQ(narrowed.status, 0) << narrowed.output;
  EXPECT_NE(narrowed.output.find("glaswave: warning: --threads 2: this process may run on 1 of "
                                 "the machine's " +
                                 std::to_string(cores) +
                                 " cores, so it runs 1 thread where 2 were meant\n"),
            std::string::npos)
      << narrowed.output;
  // Not under mpirun: no word of its binding.
  EXPECT_EQ(narrowed.output.find("mpirun"), std::string::npos) << narrowed.output;
  // --threads 0 alone means the cores it may run on (a batch system's cpuset is meant): silent.
  const CommandOutcome narrowed_all =
      run_command("taskset -c 0 " + std::string(GLASWAVE_BINARY) + " run " + config +
                  " --quiet --threads 0 --out " + (dir_ / "narrowed_all").string() + " 2>&1");
  ASSERT_EQ(narrowed_all.status, 0) << narrowed_all.output;
  EXPECT_EQ(narrowed_all.output.find("warning"), std::string::npos) << narrowed_all.output;
  // On every core, two threads are what was asked for.
  const CommandOutcome whole =
      run_glaswave("run " + config + " --quiet --threads 2 --out " + (dir_ / "whole").string());
  ASSERT_EQ(whole.status, 0) << whole.output;
  EXPECT_EQ(whole.output.find("warning"), std::string::npos) << whole.output;
}

// Each bad configuration: exit status 2, one line starting "glaswave: error:" naming the place,
// and no product.
TEST_F(Cli, BadConfigurationsFailWithOneLineNamingThePlace) {
  struct Case {
    std::string arguments, expected;
  };
  const std::string config = write_config();
  const std::vector<Case> cases = {
      {"--set canopy.pai=-1", "/canopy/pai: must be >= 0, got -1"},
      {"--set canopy.pia=2", "did you mean \"pai\""},
      {"--set simulation.rays_per_shot=0", "/simulation/rays_per_shot"},
      {"--set canopy.cover=1.5", "/canopy/cover"},
      {"--set canopy.leaf_reflectance=0.7 --set canopy.leaf_transmittance=0.5",
       "/canopy/leaf_transmittance"},
      {"--set seed=\\\"x\\\"", "/seed"},
      {"--set simulation.rays_per_shot=1e999", "/simulation/rays_per_shot"},
      {"--shots 9:12", "--shots"},
      {"--seed -1", "--seed: must be an integer in [0, 18446744073709551615], got \"-1\""},
      {"--set output.netcdf=false --set output.footprints=false", "/output: nothing to write"},
  };
  for (const Case& c : cases) {
    const CommandOutcome run = run_glaswave("run " + config + " --quiet --out " +
                                            (dir_ / "out").string() + " " + c.arguments);
    EXPECT_EQ(run.status, 2) << c.arguments << ": " << run.output;
    EXPECT_EQ(run.output.rfind("glaswave: error: ", 0), 0u) << run.output;
    EXPECT_NE(run.output.find(c.expected), std::string::npos) << c.arguments << ": " << run.output;
    EXPECT_EQ(std::count(run.output.begin(), run.output.end(), '\n'), 1) << run.output;
    EXPECT_FALSE(fs::exists(dir_ / "out")) << c.arguments;
  }
}

TEST_F(Cli, MalformedJsonNamesLineAndColumn) {
  const fs::path file = dir_ / "broken.json";
  std::ofstream(file) << "{\n  \"seed\": 1,\n  \"sensor\": {\"preset\": \"glas\",}\n}\n";
  const CommandOutcome run = run_glaswave("check " + file.string());
  EXPECT_EQ(run.status, 2);
  EXPECT_NE(run.output.find("line 3"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("column"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find(file.string()), std::string::npos) << run.output;
}

TEST_F(Cli, ExistingOutputDirectoryIsRefusedAndKept) {
  const std::string config = write_config();
  fs::create_directories(dir_ / "out");
  std::ofstream(dir_ / "out" / "mine.txt") << "a user's file";
  const CommandOutcome run =
      run_glaswave("run " + config + " --quiet --out " + (dir_ / "out").string());
  EXPECT_EQ(run.status, 2);
  EXPECT_TRUE(fs::exists(dir_ / "out" / "mine.txt"));
  EXPECT_FALSE(fs::exists(dir_ / "out" / "shots.nc"));
}

// PRODUCT.md section 2's sweep: sensitivity.csv with its columns, a base row per band with
// empty percentages, a row per value and band; the seed's signs (PHYSICS.md section 7) for PAI
// and soil reflectance over a homogeneous layer 10 m above the ground (canopy and ground apart
// in the waveform, as the seed's crowns are); sensitivity.md as the seed's Table 3.
TEST_F(Cli, SweepWritesTheSensitivityTable) {
  const std::string config = write_config({{"canopy",
                                            {{"crown_shape", "layer"},
                                             {"crown_base_m", {10.0, 10.0}},
                                             {"crown_half_height_m", 6.0},
                                             {"dbh_m", 0.0}}},
                                           {"track", {{"shots", 2}}}});
  const CommandOutcome sweep = run_glaswave(
      "sweep " + config + " --vary canopy.pai=1,5 --vary terrain.soil_reflectance=0.3 --out " +
      (dir_ / "sweep").string());
  ASSERT_EQ(sweep.status, 0) << sweep.output;
  std::ifstream csv(dir_ / "sweep" / "sensitivity.csv");
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "key,value,band,tr,cr,gr,tr_pct,cr_pct,gr_pct");
  std::map<std::string, std::array<double, 3>> change_1064;  // "key=value" -> TR, CR, GR %
  int rows = 0;
  while (std::getline(csv, line)) {
    ++rows;
    std::vector<std::string> fields;
    std::stringstream split(line);
    for (std::string field; std::getline(split, field, ',');) fields.push_back(field);
    if (fields[0] == "base") {
      EXPECT_EQ(line.substr(line.size() - 3), ",,,") << line;
      continue;
    }
    ASSERT_EQ(fields.size(), 9u) << line;
    if (fields[2] == "1064")
      change_1064[fields[0] + "=" + fields[1]] = {std::stod(fields[6]), std::stod(fields[7]),
                                                  std::stod(fields[8])};
  }
  EXPECT_EQ(rows, 2 * (1 + 3));                    // two bands: the base and three cases
  EXPECT_LT(change_1064["canopy.pai=1"][1], 0.0);  // less foliage: less canopy return...
  EXPECT_GT(change_1064["canopy.pai=1"][2], 0.0);  // ... more ground return
  EXPECT_GT(change_1064["canopy.pai=5"][1], 0.0);
  EXPECT_LT(change_1064["canopy.pai=5"][2], 0.0);
  EXPECT_GT(change_1064["terrain.soil_reflectance=0.3"][2], 50.0);  // brighter soil: GR up
  EXPECT_GT(change_1064["terrain.soil_reflectance=0.3"][0], 0.0);
  std::ifstream md(dir_ / "sweep" / "sensitivity.md");
  std::stringstream table;
  table << md.rdbuf();
  EXPECT_NE(table.str().find("| Parameter | Value | TR (%) | CR (%) | GR (%) |"),
            std::string::npos);
  EXPECT_NE(table.str().find("| canopy.pai | 3.0 (base) | - | - | - |"), std::string::npos)
      << table.str();
  // A bad value is refused before anything is simulated.
  const CommandOutcome bad =
      run_glaswave("sweep " + config + " --vary canopy.pai=1,-2 --out " + (dir_ / "bad").string());
  EXPECT_EQ(bad.status, 2);
  EXPECT_NE(bad.output.find("/canopy/pai: must be >= 0, got -2"), std::string::npos) << bad.output;
  EXPECT_FALSE(fs::exists(dir_ / "bad"));
}

// PRODUCT.md section 2's brf: brf.json in the contract's layout, scene.tif a georeferenced
// GeoTIFF of the tile at brf.image_resolution_m, one band per sensor band; the same bits on one
// thread and on two; a bad brf key refused at its JSON path with nothing written.
TEST_F(Cli, BrfWritesReflectancesAndTheSceneImage) {
  const std::string config = write_config({{"brf",
                                            {{"photons", 3000},
                                             {"scene_size_m", 40.0},
                                             {"image_resolution_m", 2.0},
                                             {"views",
                                              {{{"zenith_deg", 0.0}, {"azimuth_deg", 0.0}},
                                               {{"zenith_deg", 30.0}, {"azimuth_deg", 90.0}}}}}}});
  const CommandOutcome one =
      run_glaswave("brf " + config + " --quiet --threads 1 --out " + (dir_ / "one").string());
  ASSERT_EQ(one.status, 0) << one.output;
  const CommandOutcome two =
      run_glaswave("brf " + config + " --quiet --threads 2 --out " + (dir_ / "two").string());
  ASSERT_EQ(two.status, 0) << two.output;
  auto text = [](const fs::path& file) {
    std::ostringstream content;
    content << std::ifstream(file).rdbuf();
    return content.str();
  };
  EXPECT_EQ(text(dir_ / "one" / "brf.json"), text(dir_ / "two" / "brf.json"));
  const nlohmann::json brf = nlohmann::json::parse(text(dir_ / "one" / "brf.json"));
  ASSERT_EQ(brf["bands"].size(), 2u);  // the glas preset's 532 and 1064
  EXPECT_EQ(brf["bands"][0]["name"], "532");
  for (const auto& band : brf["bands"]) {
    // Bare ground of reflectance 0.15 (the default) tilted 8 degrees: Lambertian.
    EXPECT_GT(band["albedo"].get<double>(), 0.1);
    EXPECT_LT(band["albedo"].get<double>(), 0.2);
    ASSERT_EQ(band["views"].size(), 2u);
    EXPECT_EQ(band["views"][1]["zenith_deg"], 30.0);
    EXPECT_EQ(band["views"][1]["azimuth_deg"], 90.0);
    for (const auto& view : band["views"]) {
      EXPECT_GT(view["brf"].get<double>(), 0.1);
      EXPECT_GE(view["brf_stderr"].get<double>(), 0.0);
    }
  }
  GDALAllRegister();
  GDALDatasetUniquePtr image(
      GDALDataset::Open((dir_ / "one" / "scene.tif").c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
  ASSERT_TRUE(image);
  EXPECT_EQ(image->GetRasterXSize(), 20);
  EXPECT_EQ(image->GetRasterYSize(), 20);
  EXPECT_EQ(image->GetRasterCount(), 2);
  double transform[6];
  ASSERT_EQ(image->GetGeoTransform(transform), CE_None);
  EXPECT_DOUBLE_EQ(transform[0], -20.0);
  EXPECT_DOUBLE_EQ(transform[1], 2.0);
  EXPECT_DOUBLE_EQ(transform[5], -2.0);
  ASSERT_NE(image->GetSpatialRef(), nullptr);
  EXPECT_TRUE(image->GetSpatialRef()->IsProjected());
  EXPECT_FALSE(fs::exists(dir_ / "one" / "scene.tif.part"));

  const CommandOutcome bad =
      run_glaswave("brf " + config + " --set brf.photons=0 --out " + (dir_ / "bad").string());
  EXPECT_EQ(bad.status, 2);
  EXPECT_NE(bad.output.find("glaswave: error: /brf/photons: must be >= 1, got 0"),
            std::string::npos)
      << bad.output;
  const CommandOutcome typo =
      run_glaswave("brf " + config + " --set brf.sun_zenith=10 --out " + (dir_ / "bad").string());
  EXPECT_EQ(typo.status, 2);
  EXPECT_NE(typo.output.find("/brf/sun_zenith: unknown key"), std::string::npos) << typo.output;
  EXPECT_FALSE(fs::exists(dir_ / "bad"));
}

TEST_F(Cli, CheckHelpAndVersion) {
  const CommandOutcome check = run_glaswave("check " + write_config());
  EXPECT_EQ(check.status, 0) << check.output;
  EXPECT_NE(check.output.find("5 shots"), std::string::npos) << check.output;
  const CommandOutcome help = run_glaswave("--help");
  EXPECT_EQ(help.status, 0);
  EXPECT_NE(help.output.find("run"), std::string::npos);
  EXPECT_NE(help.output.find("check"), std::string::npos);
  const CommandOutcome version = run_glaswave("--version");
  EXPECT_EQ(version.status, 0);
  EXPECT_NE(version.output.find("glaswave " GLASWAVE_VERSION), std::string::npos) << version.output;
  const CommandOutcome bad = run_glaswave("fly");
  EXPECT_EQ(bad.status, 2);
  EXPECT_EQ(bad.output.rfind("glaswave: error: ", 0), 0u) << bad.output;
}

}  // namespace
}  // namespace glaswave
