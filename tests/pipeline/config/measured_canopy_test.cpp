// canopy.voxels and canopy.point_cloud (PRODUCT.md section 8): read into the canopy's settings,
// alone in the canopy, their leaves' keys checked as the crowns' are.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tests/pipeline/config/config_test_support.hpp"

namespace glaswave {
namespace {

using test_support::doc;
using test_support::error_of;
using ::testing::HasSubstr;
using ::testing::StartsWith;

TEST(MeasuredCanopy, VoxelsAndPointClouds) {
  const Config v = parse_config(doc(R"({"canopy": {"voxels": {"file": "pad.nc",
      "lad": "planophile", "leaf_size_m": 0.1, "leaf_reflectance": {"532": 0.05, "1064": 0.45},
      "bark_fraction": 0.25}}})"));
  ASSERT_TRUE(v.canopy);
  EXPECT_EQ(v.canopy->voxels_file, "pad.nc");
  EXPECT_EQ(v.canopy->point_cloud_file, "");
  EXPECT_EQ(v.canopy->lad, LeafAngleDistribution::planophile);
  EXPECT_EQ(v.canopy->leaf_size_m, 0.1);
  EXPECT_EQ(v.canopy->bark_fraction, 0.25);
  EXPECT_EQ(v.canopy->green_fraction, 0.75);
  ASSERT_EQ(v.canopy->leaf_reflectance.size(), 2u);
  EXPECT_EQ(v.canopy->leaf_reflectance[1], 0.45);
  EXPECT_EQ(v.resolved["canopy"]["voxels"]["file"], "pad.nc");
  EXPECT_EQ(v.resolved["canopy"]["voxels"]["leaf_transmittance"], 0.4);

  const Config p = parse_config(doc(R"({"canopy": {"point_cloud": {"file": "plot.las",
      "crs": "EPSG:32633", "voxel_size_m": 2}}})"));
  EXPECT_EQ(p.canopy->point_cloud_file, "plot.las");
  EXPECT_EQ(p.canopy->point_cloud_crs, "EPSG:32633");
  EXPECT_EQ(p.canopy->voxel_size_m, 2.0);
  EXPECT_EQ(p.canopy->bark_fraction, 0.0);  // a grid of leaves unless said otherwise
}

TEST(MeasuredCanopy, RefusesWhatCannotBe) {
  EXPECT_THAT(error_of(doc(R"({"canopy": {"pai": 2, "voxels": {"file": "pad.nc"}}})")),
              StartsWith("/canopy/pai: cannot be given beside canopy.voxels"));
  EXPECT_THAT(error_of(doc(R"({"canopy": {"voxels": {}}})")),
              StartsWith("/canopy/voxels/file: is required"));
  EXPECT_THAT(error_of(doc(R"({"canopy": {"point_cloud": {"file": "a.las", "voxel_size_m": 0}}})")),
              StartsWith("/canopy/point_cloud/voxel_size_m: must be in [0.05, 100]"));
  EXPECT_THAT(error_of(doc(R"({"canopy": {"voxels": {"file": "a.nc", "leaf_reflectance": 0.7,
      "leaf_transmittance": 0.5}}})")),
              HasSubstr("leaf_reflectance + leaf_transmittance must be <= 1"));
  EXPECT_THAT(error_of(doc(R"({"canopy": {"voxels": {"file": "a.nc", "lads": "x"}}})")),
              StartsWith("/canopy/voxels/lads: unknown key"));
}

}  // namespace
}  // namespace glaswave
