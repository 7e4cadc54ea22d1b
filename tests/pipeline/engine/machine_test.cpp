// The memory a run or `brf` would hold, estimated from the configuration before anything is
// allocated (pipeline/engine/machine.hpp), and refused with the limit in the message at the key
// that makes it large.
#include "pipeline/engine/machine.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>

#include "canopy/voxel_grid.hpp"
#include "core/error.hpp"
#include "pipeline/config/config.hpp"
#include "pipeline/engine/inputs.hpp"
#include "pipeline/shot/voxel_source.hpp"
#include "tests/canopy/las_fixture.hpp"
#include "tests/pipeline/config/config_test_support.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

using nlohmann::json;
using namespace test_support;  // doc, error_of
using ::testing::HasSubstr;
using ::testing::StartsWith;

// The estimate against the numbers computed here from the same geometry: the glas preset's
// field of view from 600 km, 1.2 times its reach plus 2 m and 100 m of margin for the forest's
// diffuse light, and random crowns at -ln(1 - cover) / (pi r^2) a square metre.
TEST(RunMemory, CountsTheTreesUnderTheFieldOfView) {
  const Config c = parse_config(doc(R"({"sensor": {"preset": "glas"}, "canopy": {}})"));
  const RunMemory m = estimate_run_memory(c);
  const double half_m = 1.2 * 600000.0 * std::tan(0.5 * c.sensor.ifov_rad) + 102.0;
  EXPECT_NEAR(m.scene_half_size_m, half_m, 1e-6);
  const double density = -std::log(1.0 - 0.7) / (std::numbers::pi * 8.0 * 8.0);
  EXPECT_NEAR(m.trees, density * 4.0 * half_m * half_m, 1e-6 * m.trees);
  EXPECT_NEAR(m.bytes, m.program_bytes + m.threads * (m.trees * 2560.0 + m.waveform_bytes), 1.0);
  EXPECT_GT(m.available_bytes, 0.0);
  EXPECT_NO_THROW(check_run(c));
  // Bare ground has no trees; a layer neither.
  EXPECT_EQ(estimate_run_memory(parse_config(doc("{}"))).trees, 0.0);
  EXPECT_EQ(estimate_run_memory(parse_config(doc(R"({"canopy": {"crown_shape": "layer"}})"))).trees,
            0.0);
}

TEST(RunMemory, BeyondTheMachineIsRefusedAtTheKeyThatMakesIt) {
  // 1 cm crowns: about 1e9 trees a shot, terabytes.
  const Config dense = parse_config(doc(R"({"canopy": {"crown_radius_m": 0.01}})"));
  try {
    check_run(dense);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.place(), "/canopy/crown_radius_m");
    EXPECT_THAT(e.message(), StartsWith("a run would hold about "));
    EXPECT_THAT(e.message(), HasSubstr(" of memory this process may have"));
  }
  // The widest field of view from the highest altitude: a scene 2400 km across.
  const Config wide = parse_config(
      doc(R"({"sensor": {"ifov_rad": 0.05}, "track": {"altitude_m": 4e7}, "canopy": {}})"));
  try {
    check_run(wide);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.place(), "/track/altitude_m");
  }
}

// A voxel grid's region: the window of the grid a shot reads, packed (its columns' densities, 4
// bytes a voxel at most, 12 bytes of index and the ground under each, 8 bytes; read by bands of
// a MiB), counted here on the field a VoxelSource grows over the estimate's half size about
// 45 N 7 E: the estimate within 2 % of it. 2 m columns, 30 layers of one density, a 1200 m
// square in UTM 32N; the glas preset's scene is 492 m across (247 x 247 columns of 140 bytes,
// 8.1 MiB, and the band).
TEST(RunMemory, CountsTheVoxelGridsWindowEachThreadHolds) {
  test_support::ScratchDir dir;
  VoxelBlock grid;
  grid.crs_wkt = "EPSG:32632";
  grid.nx = grid.ny = 600;
  grid.nz = 30;
  grid.dx = grid.dy = 2.0;
  grid.x0 = 342369.0 - 600.0;
  grid.y0 = 4984896.0 - 600.0;
  for (int k = 0; k <= grid.nz; ++k) grid.z_edges_m.push_back(k);
  grid.pad.assign(std::size_t(600) * 600 * 30, 0.25f);
  write_voxel_netcdf(dir.path() / "pad.nc", grid);
  json document = doc(R"({"sensor": {"preset": "glas"}, "terrain": {"plane": {"origin_lat_deg": 45,
      "origin_lon_deg": 7}}})");
  document["canopy"] = {{"voxels", {{"file", (dir.path() / "pad.nc").string()}}}};
  const Config c = parse_config(document);
  const RunMemory m = estimate_run_memory(c);
  const auto terrain = make_terrain(c.terrain);
  const VoxelSource source(vegetation_settings(c));
  const LocalFrame frame({45.0, 7.0, 0.0});
  const auto field = source.grow({*terrain, frame, m.scene_half_size_m, {}, 1}).geometry.voxels;
  ASSERT_TRUE(field);
  // The window's ground and index, and a tile as read: the whole grid (600 x 600 columns of 30
  // floats and an index, 47 MiB) fits the tile cache, which source_bytes counts once.
  const double window_bytes = field->ground_m.size() * 8.0 +
                              field->columns.size() * sizeof(VoxelField::Column) +
                              64.0 * 64 * 30 * 4;
  EXPECT_NEAR(m.scene_bytes / window_bytes, 1.0, 0.02) << field->nx << " x " << field->ny;
  EXPECT_EQ(m.trees, 0.0);
  // Once for the run: the grid's decompressed chunks NetCDF keeps, those 2 x 2 tiles of 64
  // columns meet at worst: 3 x 3 chunks of 64 x 64 columns, 4.2 MiB; and the packed tiles
  // kept between shots, here the whole grid (600 x 600 columns of 30 floats and an index).
  EXPECT_EQ(m.source_bytes,
            192.0 * 192 * 30 * 4 + 600.0 * 600 * (30 * 4 + sizeof(VoxelField::Column)));
  EXPECT_NEAR(m.bytes,
              m.program_bytes + m.source_bytes + m.threads * (m.scene_bytes + m.waveform_bytes),
              1.0);
  EXPECT_NO_THROW(check_run(c));
}

// A point cloud is voxelised once when the run starts: each voxel's weight and density, over the
// columns its header's extent spans at voxel_size_m and the 120 m the inversion keeps. Two
// points 20 km apart at 5 cm: 1.6e11 columns of 2400 layers, far beyond any machine, refused at
// the voxel size.
TEST(RunMemory, APointCloudsVoxelisationIsRefusedAtItsVoxelSize) {
  test_support::ScratchDir dir;
  test::LasFixture las;
  las.points.resize(2);
  las.points[0].x = 500000.0;
  las.points[0].y = 4000000.0;
  las.points[1].x = 520000.0;
  las.points[1].y = 4020000.0;
  las.points[1].z = 30.0;
  test::write_las(dir.path() / "wide.las", las);
  json document = doc("{}");
  document["canopy"] = {{"point_cloud",
                         {{"file", (dir.path() / "wide.las").string()},
                          {"crs", "EPSG:32633"},
                          {"voxel_size_m", 0.05}}}};
  const Config c = parse_config(document);
  const RunMemory m = estimate_run_memory(c);
  const double columns = (20000.0 / 0.05 + 1) * (20000.0 / 0.05 + 1);
  EXPECT_NEAR(m.source_bytes / (columns * (2401 * 8.0 + 2400 * 4.0 + 24.0)), 1.0, 1e-5);
  // Each thread's window: the packed tiles of 64 x 64 columns it meets at worst (one more each
  // way than its columns fill), 31 m of heights in 5 cm layers (the header's z range and one
  // more) and an index entry a column; the window's ground and index; a tile as read.
  const double side_m = 2.0 * m.scene_half_size_m, across = side_m / 0.05 + 1;
  const double tiles = std::pow(std::ceil((across - 1) / 64) + 1, 2);
  EXPECT_NEAR(
      m.scene_bytes,
      tiles * 64 * 64 * (601 * 4.0 + 16.0) + across * across * (8.0 + 16.0) + 64 * 64 * 601 * 4.0,
      1e-6 * m.scene_bytes);
  try {
    check_run(c);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.place(), "/canopy/point_cloud/voxel_size_m");
    EXPECT_THAT(e.message(), HasSubstr("; the point_cloud source's "));
  }
}

// Facet models are read once for the run, at 20 bytes of memory a byte of their file (Assimp's
// read of an OBJ at its peak, measured by facet_benchmark): a model file of 2 TiB (sparse) is
// refused at the models before anything reads it. Each thread's scene holds the region's
// instances, a tree every 20 m2 at 256 bytes.
TEST(RunMemory, FacetModelsAreCountedOnceAndRefusedAtTheModels) {
  test_support::ScratchDir dir;
  const auto huge = dir.path() / "huge.obj";
  std::ofstream(huge) << "v 0 0 0\n";
  std::filesystem::resize_file(huge, std::uintmax_t{2} << 40);
  std::ofstream(dir.path() / "trees.csv") << "x,y,model,rotation_deg,scale\n0,0,tree,0,1\n";
  json document = doc(R"({"sensor": {"preset": "gedi"}})");
  document["canopy"] = {{"facets",
                         {{"trees_file", (dir.path() / "trees.csv").string()},
                          {"models", {{"tree", huge.string()}}},
                          {"materials", {{"leaf", {{"reflectance", 0.4}}}}}}}};
  const Config c = parse_config(document);
  const RunMemory m = estimate_run_memory(c);
  EXPECT_EQ(m.source_bytes, 20.0 * std::pow(2.0, 41));
  const double side_m = 2.0 * m.scene_half_size_m;
  EXPECT_NEAR(m.scene_bytes, side_m * side_m / 20.0 * 256.0, 1e-6);
  try {
    check_run(c);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.place(), "/canopy/facets/models");
    EXPECT_THAT(e.message(), HasSubstr("; the facets source's "));
  }
}

// brf's scene: one for every thread, its tile in whole pixels with 5 m beyond each side over a
// periodic plane, the trees on it at -ln(1 - cover) / (pi r^2) a square metre, and scene.tif's
// bands of 8-byte pixels held twice.
TEST(BrfMemory, CountsTheTreesOfTheTileAndTheImage) {
  const Config c = parse_config(doc(R"({"sensor": {"preset": "glas"}, "canopy": {},
      "brf": {"scene_size_m": 99.5, "image_resolution_m": 2}})"));
  const BrfMemory m = estimate_brf_memory(c);
  EXPECT_EQ(m.pixels, 50.0);
  EXPECT_EQ(m.scene_side_m, 110.0);
  const double density = -std::log(1.0 - 0.7) / (std::numbers::pi * 8.0 * 8.0);
  EXPECT_NEAR(m.trees, density * 110.0 * 110.0, 1e-9 * m.trees);
  EXPECT_NEAR(m.image_bytes, 2.0 * 50 * 50 * 8 * 2, 1e-9);  // glas: 2 bands
  EXPECT_NEAR(m.bytes, m.program_bytes + m.trees * 2560.0 + m.image_bytes, 1e-6);
  EXPECT_NO_THROW(check_brf(c));
  // Over a DEM the scene reaches 100 m beyond the tile.
  const Config dem = parse_config(doc(R"({"terrain": {"dem": "x.tif"}, "brf": {}})"));
  EXPECT_EQ(estimate_brf_memory(dem).scene_side_m, 500.0);  // the default 300 m tile
}

TEST(BrfMemory, ATileThatCannotBePhysicalOrFitIsRefusedAtItsKey) {
  EXPECT_EQ(error_of(doc(R"({"brf": {"scene_size_m": 20000}})")),
            "/brf/scene_size_m: must be in (0, 10000], got 20000");
  const auto refusal = [](const std::string& text) {
    try {
      check_brf(parse_config(doc(text)));
    } catch (const Error& e) {
      return e.place() + ": " + e.message();
    }
    return std::string("accepted");
  };
  EXPECT_EQ(refusal(R"({"brf": {"scene_size_m": 10000, "image_resolution_m": 0.5}})"),
            "/brf/image_resolution_m: scene.tif would be 20000 pixels across (10000 m at 0.5 m a "
            "pixel); at most 8192");
  EXPECT_EQ(refusal(R"({"brf": {"scene_size_m": 8192, "image_resolution_m": 1}})"), "accepted");
  // 5 cm crowns over the widest tile: 3e10 trees, tens of terabytes.
  EXPECT_THAT(refusal(R"({"canopy": {"crown_radius_m": 0.05, "cover": 0.9},
      "brf": {"scene_size_m": 10000, "image_resolution_m": 10}})"),
              StartsWith("/brf/scene_size_m: brf's scene would hold about "));
  EXPECT_THAT(refusal(R"({"canopy": {"crown_radius_m": 0.01}})"),
              StartsWith("/canopy/crown_radius_m: brf's scene would hold about "));
  // 256 bands of 8192 x 8192 pixels: 256 GiB of image, and the program's 52 MiB.
  json bands = json::array();
  for (int i = 0; i < 256; ++i)
    bands.push_back({{"name", std::string("b").append(std::to_string(i))},
                     {"wavelength_nm", 500 + i},
                     {"pulse_energy_mJ", 1},
                     {"atmos_transmission_roundtrip", 0.9}});
  const std::string many_bands = json{
      {"sensor", {{"bands", bands}, {"bins", 100}}},
      {"canopy", nullptr},
      {"brf",
       {{"scene_size_m", 8192}}}}.dump();
  EXPECT_THAT(refusal(many_bands),
              StartsWith("/brf/image_resolution_m: brf's scene would hold about 256.1 GiB"));
}

}  // namespace
}  // namespace glaswave

namespace glaswave {
namespace {

// Issue 42: check's estimate left out the ICESat-2 granules' photons, held to the end of a run
// (7.6 MiB whatever the pass; 0.8 kB a shot and beam measured). A pass of 10^6 shots of two
// beams holds 1.6 GB of them; 10^9 shots of six beams (4.8 TB) are refused at /track/shots.
TEST(RunMemory, CountsTheIcesatGranulesPhotonsHeldToTheEnd) {
  const Config pass = parse_config(doc(R"({"sensor": {"preset": "atlas",
      "beams": ["gt1l", "gt2l"]}, "track": {"shots": 1000000}})"));
  const RunMemory m = estimate_run_memory(pass);
  EXPECT_DOUBLE_EQ(m.granule_bytes, 800.0 * 1e6 * 2);
  EXPECT_DOUBLE_EQ(m.bytes, m.program_bytes + m.source_bytes + m.granule_bytes +
                                m.threads * (m.scene_bytes + m.waveform_bytes));
  const Config without = parse_config(doc(R"({"sensor": {"preset": "atlas"},
      "track": {"shots": 1000000}, "output": {"atl03": false, "atl08": false,
      "netcdf": true}})"));
  EXPECT_EQ(estimate_run_memory(without).granule_bytes, 0.0);
  const Config huge = parse_config(doc(R"({"sensor": {"preset": "atlas", "beams": ["gt1l",
      "gt1r", "gt2l", "gt2r", "gt3l", "gt3r"]}, "track": {"shots": 1000000000}})"));
  try {
    check_run(huge);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.place(), "/track/shots");
    EXPECT_THAT(e.message(), HasSubstr("the ICESat-2 granules' photons, "));
  }
}

}  // namespace
}  // namespace glaswave
