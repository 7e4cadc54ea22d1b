// glaswave voxelize end to end: a LAS 1.4 cloud of a level 10 m x 10 m plot (ground returns,
// and half the pulses' beamlets stopped in a layer 8-10 m up) -> grid.nc that the voxel reader
// takes back, its crown layer's density the Beer-Lambert value; and the refusals of PRODUCT.md
// section 5: LAZ, no CRS, a bad voxel size; and an --out it would lose or cannot use, refused
// before anything is computed (issue 42).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "canopy/voxel_grid.hpp"
#include "tests/canopy/las_fixture.hpp"
#include "tests/pipeline/engine/engine_test_support.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

// 400 pulses of one return each on a 0.5 m lattice: every other one hits the layer at 9 m.
// P(8 m) = 1/2 of P(10 m): PAD = ln 2 / (G 2 m) with G = 1/2, vertical pulses.
test::LasFixture plot_cloud() {
  test::LasFixture f;
  f.version_minor = 4;
  f.point_format = 6;
  for (int j = 0; j < 20; ++j)
    for (int i = 0; i < 20; ++i) {
      test::LasFixturePoint p;
      p.x = 500000.25 + 0.5 * i;
      p.y = 4000000.25 + 0.5 * j;
      const bool hit = (i + j) % 2 == 0;
      p.z = 100.0 + (hit ? 9.0 : 0.0);
      p.classification = hit ? 5 : 2;
      f.points.push_back(p);
    }
  return f;
}

TEST(Voxelize, WritesTheGridOfAPointCloud) {
  test_support::ScratchDir dir;
  test::write_las(dir.path() / "plot.las", plot_cloud());
  const auto out = dir.path() / "grid.nc";
  const auto result =
      test_support::run_glaswave("voxelize " + (dir.path() / "plot.las").string() + " --out " +
                                 out.string() + " --voxel-size-m 2 --crs EPSG:32633");
  ASSERT_EQ(result.status, 0) << result.output;
  EXPECT_NE(result.output.find("400 points (200 ground"), std::string::npos) << result.output;
  const VoxelGridFile grid(out);
  EXPECT_EQ(grid.shape().nx, 5);
  EXPECT_EQ(grid.shape().ny, 5);
  EXPECT_EQ(grid.shape().nz, 5);  // up to the crown layer, 8-10 m
  EXPECT_NE(grid.shape().crs_wkt.find("UTM zone 33N"), std::string::npos);
  const VoxelBlock all = grid.window(-1e9, 1e9, -1e9, 1e9);
  for (int j = 0; j < 5; ++j)
    for (int i = 0; i < 5; ++i) {
      EXPECT_NEAR(all.at(i, j, 4), std::log(2.0) / (0.5 * 2.0), 1e-5);
      for (int k = 0; k < 4; ++k) EXPECT_EQ(all.at(i, j, k), 0.0f);
    }
}

TEST(Voxelize, RefusesWhatItCannotUse) {
  test_support::ScratchDir dir;
  const std::string out = " --out " + (dir.path() / "grid.nc").string();
  test::write_las(dir.path() / "plot.las", plot_cloud());
  const std::string cloud = (dir.path() / "plot.las").string();
  auto r = test_support::run_glaswave("voxelize " + cloud + out);
  EXPECT_EQ(r.status, 3) << r.output;
  EXPECT_NE(r.output.find("no CRS"), std::string::npos) << r.output;
  r = test_support::run_glaswave("voxelize " + cloud + out + " --crs EPSG:32633 --voxel-size-m 0");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("--voxel-size-m"), std::string::npos) << r.output;
  r = test_support::run_glaswave("voxelize " + cloud + out + " --crs nonsense");
  EXPECT_EQ(r.status, 2) << r.output;
  test::write_las(dir.path() / "plot.laz", plot_cloud());
  r = test_support::run_glaswave("voxelize " + (dir.path() / "plot.laz").string() + out);
  EXPECT_EQ(r.status, 3) << r.output;
  EXPECT_NE(r.output.find("laszip"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("glaswave: error:"), 0u) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "grid.nc"));
}

// An existing --out is refused as `run` refuses one, unless --force; the cloud itself, a
// directory or a device even with it; a missing folder said to be missing.
TEST(Voxelize, RefusesAnOutputItWouldLose) {
  test_support::ScratchDir dir;
  test::write_las(dir.path() / "plot.las", plot_cloud());
  const std::string cloud = (dir.path() / "plot.las").string();
  const std::string line = "voxelize " + cloud + " --crs EPSG:32633 --voxel-size-m 2 --out ";
  const auto grid = dir.path() / "grid.nc";
  std::ofstream(grid) << "the user's own file";
  auto r = test_support::run_glaswave(line + grid.string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("grid.nc: --out exists"), std::string::npos) << r.output;
  EXPECT_EQ(std::filesystem::file_size(grid), 19u);
  r = test_support::run_glaswave(line + grid.string() + " --force");
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(VoxelGridFile(grid).shape().nx, 5);
  const auto before = std::filesystem::file_size(cloud);
  r = test_support::run_glaswave(line + cloud + " --force");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("the point cloud itself"), std::string::npos) << r.output;
  EXPECT_EQ(std::filesystem::file_size(cloud), before);
  r = test_support::run_glaswave(line + (dir.path() / "none" / "grid.nc").string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("does not exist"), std::string::npos) << r.output;
  r = test_support::run_glaswave(line + dir.path().string() + " --force");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("is a directory"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("points"), std::string::npos) << r.output;  // nothing computed
  r = test_support::run_glaswave(line + "/dev/null --force");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("not a regular file"), std::string::npos) << r.output;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
    EXPECT_NE(entry.path().extension(), ".part") << entry.path();
}

}  // namespace
}  // namespace glaswave
