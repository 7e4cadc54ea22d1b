// The footprint's patch, as the shot builds it and the memory estimate foresees it.
#include "pipeline/shot/footprint_geometry.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/pipeline/shot/shot_test_support.hpp"

namespace glaswave {
namespace {

using namespace glaswave::testing;

TEST(FootprintGeometry, PatchIsTheReachWithAMargin) {
  EXPECT_DOUBLE_EQ(patch_half_size_m(10.0), 14.0);  // 1.2 x 10 m + 2 m
  // The field of view's edge from 600 km at 0.2 mrad is 120.0000016 m from the centre; on a
  // 60-degree slope twice that.
  EXPECT_NEAR(estimated_patch_half_size_m(600000.0, 0.0004, 0.0, false), 146.0000019, 1e-6);
  EXPECT_NEAR(estimated_patch_half_size_m(600000.0, 0.0004, 60.0, true), 390.0000038, 1e-6);
  EXPECT_DOUBLE_EQ(brf_scene_half_size_m(150.0, true), 155.0);
  EXPECT_DOUBLE_EQ(brf_scene_half_size_m(150.0, false), 250.0);
}

// At nadir over a level plane the traced patch is the estimated one: both reach the field of
// view's edge.
TEST(FootprintGeometry, TracedPatchAtNadirOverAPlane) {
  const std::unique_ptr<Terrain> terrain = plane_terrain();
  const Footprint footprint = nadir_footprint(*terrain);
  const LidarModel lidar(shot_settings(0.25).lidar);
  const FootprintFrame where = footprint_frame(*terrain, lidar, footprint);
  const double traced_m =
      traced_patch_half_size_m(*terrain, lidar, footprint, where.frame, lidar.max_angle_rad());
  EXPECT_NEAR(traced_m, estimated_patch_half_size_m(footprint.range_m, 0.0004, 0.0, false), 0.05);
  EXPECT_NEAR(where.orientation.slope_deg, 0.0, 1e-6);
}

}  // namespace
}  // namespace glaswave
