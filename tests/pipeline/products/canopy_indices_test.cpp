// Tests of the waveform index (the seed's eq. 3) and ICESat-2's photon-ratio covers on numbers
// worked by hand: a canopy of known cover C returning photons in proportion to rhov C and the
// ground to rhog (1 - C), from which the reflectance-corrected ratio recovers C exactly.
#include "pipeline/products/canopy_indices.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

namespace glaswave {
namespace {

TEST(WaveformIndex, IsTheSeedsNormalisedDifference) {
  EXPECT_DOUBLE_EQ(waveform_index(3.0, 1.0), 0.5);
  EXPECT_DOUBLE_EQ(waveform_index(1.0, 3.0), -0.5);
  EXPECT_DOUBLE_EQ(waveform_index(0.0, 2.0), -1.0);  // bare ground
  EXPECT_DOUBLE_EQ(waveform_index(2.0, 0.0), 1.0);   // no ground seen
  EXPECT_TRUE(std::isnan(waveform_index(0.0, 0.0)));
  EXPECT_TRUE(std::isnan(waveform_index(std::nan(""), 1.0)));
  // Insensitive to the calibration: both returns scaled alike.
  EXPECT_DOUBLE_EQ(waveform_index(3e-15, 1e-15), 0.5);
}

// Two Gaussians of areas 120 (centre 100) and 80 (centre 300), split half way: CR and GR are
// their areas, to the tails beyond 10 sigma (1e-23), so WI = (120 - 80) / 200 = 0.2.
TEST(WaveformIndex, SplitByPositionGivesEachReturnsArea) {
  const double sigma = 10.0;
  std::vector<double> values(400, 3.0);  // noise mean 3
  for (int i = 0; i < 400; ++i) {
    const double norm = 1.0 / (sigma * std::sqrt(2.0 * std::numbers::pi));
    values[i] += 120.0 * norm * std::exp(-0.5 * std::pow((i - 100.0) / sigma, 2)) +
                 80.0 * norm * std::exp(-0.5 * std::pow((i - 300.0) / sigma, 2));
  }
  const CanopyGroundReturns r = split_returns(values, 3.0, 0.0, 200.0, 399.0);
  EXPECT_NEAR(r.canopy, 120.0, 1e-9);
  EXPECT_NEAR(r.ground, 80.0, 1e-9);
  EXPECT_NEAR(waveform_index(r.canopy, r.ground), 0.2, 1e-11);
}

TEST(PhotonRatioCover, CountsAtl08Classes) {
  const std::vector<std::uint8_t> flags = {0, 1, 1, 2, 3, 2, 1, 0};
  const PhotonClassCounts c = count_photon_classes(flags);
  EXPECT_EQ(c.ground, 3);
  EXPECT_EQ(c.canopy, 2);
  EXPECT_EQ(c.top_of_canopy, 1);
  const PhotonCover cover = photon_ratio_cover(c, 1.5);
  EXPECT_DOUBLE_EQ(cover.photon_ratio, 3.0 / 6.0);
  EXPECT_DOUBLE_EQ(cover.reflectance_corrected, 3.0 / (3.0 + 1.5 * 3.0));
}

// Cover 0.7 with rhov 0.6 and rhog 0.4: 1000 rhov C = 420 canopy photons and 1000 rhog (1 - C) =
// 120 ground photons. The plain ratio reads 420 / 540 = 0.778; corrected by rhov / rhog = 1.5 it
// reads 0.7, the truth.
TEST(PhotonRatioCover, ReflectanceCorrectionRecoversTheCover) {
  const PhotonCover cover =
      photon_ratio_cover({.ground = 120, .canopy = 300, .top_of_canopy = 120}, 0.6 / 0.4);
  EXPECT_NEAR(cover.photon_ratio, 420.0 / 540.0, 1e-15);
  EXPECT_NEAR(cover.reflectance_corrected, 0.7, 1e-15);
  EXPECT_TRUE(std::isnan(photon_ratio_cover({}, 1.5).photon_ratio));
}

}  // namespace
}  // namespace glaswave
