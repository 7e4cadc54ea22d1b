// Tests of GEDI L2A's six setting groups on analytic pulses: a Gaussian of amplitude A and sigma
// s smoothed by a Gaussian of width w is a Gaussian of sigma S = sqrt(s^2 + w^2) and amplitude
// A s / S, so it crosses k noise standard deviations above the noise mean at
// mu -+ S sqrt(2 ln(A s / (S k sigma_n))): each group's toploc and botloc, hence rh100 and rh0,
// computed here by hand; rh50 from the Gaussian's cumulative integral (erf). The selection: the
// group that identifies the lowest non-noise mode, the default a1 when all agree.
#include "pipeline/products/gedi_l2a_groups.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

namespace glaswave {
namespace {

constexpr int kBins = 600;
constexpr double kBinM = 0.15;  // GEDI's 1 ns samples
constexpr double kTopM = 500.0;
const WaveformAxis kAxis{1.0, kTopM, kTopM - (kBins - 1) * kBinM};
constexpr double kNoiseMean = 10.0, kNoiseSd = 1.0;

double elevation(double bin) { return kTopM - bin * kBinM; }

std::vector<double> waveform(const std::vector<GaussianComponent>& parts) {
  std::vector<double> values(kBins, kNoiseMean);
  for (int i = 0; i < kBins; ++i)
    for (const GaussianComponent& g : parts) values[i] += g.value_at(i);
  return values;
}

// Where the smoothed Gaussian crosses k sigma_n: its distance from the centre, in bins.
double reach(double amplitude, double sigma, double width, double k) {
  const double smoothed_sigma = std::hypot(sigma, width);
  const double smoothed_amplitude = amplitude * sigma / smoothed_sigma;
  return smoothed_sigma * std::sqrt(2.0 * std::log(smoothed_amplitude / (k * kNoiseSd)));
}

// The setting groups as issue 37 and the ATBD list them.
TEST(GediL2aGroups, AreTheMissions) {
  const double zcross[] = {6.5, 3.5, 3.5, 6.5, 3.5, 3.5};
  const double front[] = {3, 3, 3, 6, 3, 3}, back[] = {6, 3, 6, 6, 2, 4};
  for (int k = 0; k < kL2aGroups; ++k) {
    EXPECT_EQ(kGediL2aGroups[k].smooth_width_bins, 6.5);
    EXPECT_EQ(kGediL2aGroups[k].zcross_width_bins, zcross[k]);
    EXPECT_EQ(kGediL2aGroups[k].front_sigmas, front[k]);
    EXPECT_EQ(kGediL2aGroups[k].back_sigmas, back[k]);
  }
}

// A lone pulse (A 50, sigma 5 bins, on bin 300) over a noise mean of 10: every group's crossings
// as computed by hand, to 0.05 bin (the crossing is interpolated linearly on the tail's curve:
// at most |f''/f'| / 8 ~ 0.03 bin); the ground at the centre; rh0 and rh100 the crossings.
TEST(GediL2aGroups, LonePulseCrossesWhereComputedByHand) {
  const double amplitude = 50.0, center = 300.0, sigma = 5.0;
  const auto values = waveform({{amplitude, center, sigma}});
  const L2aWaveform input{values, kAxis, kNoiseMean, kNoiseSd};
  for (int k = 0; k < kL2aGroups; ++k) {
    const L2aGroupSettings& g = kGediL2aGroups[k];
    const L2aGroupResult r = process_l2a_group(input, g);
    SCOPED_TRACE(testing::Message() << "a" << k + 1);
    ASSERT_TRUE(r.signal);
    ASSERT_TRUE(r.has_ground);
    const double top = center - reach(amplitude, sigma, g.smooth_width_bins, g.front_sigmas);
    const double bottom = center + reach(amplitude, sigma, g.smooth_width_bins, g.back_sigmas);
    EXPECT_NEAR(r.toploc_bin, top, 0.05);
    EXPECT_NEAR(r.botloc_bin, bottom, 0.05);
    EXPECT_EQ(r.num_detectedmodes, 1);
    EXPECT_NEAR(r.lowestmode_bin, center, 1e-6);
    EXPECT_NEAR(r.elev_lowestmode_m, elevation(center), 1e-6);
    EXPECT_NEAR(r.elev_highestreturn_m, elevation(top), 0.05 * kBinM);
    EXPECT_NEAR(r.rh_m[100], (center - top) * kBinM, 0.05 * kBinM);
    EXPECT_NEAR(r.rh_m[0], -(bottom - center) * kBinM, 0.05 * kBinM);
    // rh50: half the energy between the crossings lies below it. With u = (x - mu) / s,
    // Phi(u50) = (Phi(u_bottom) + Phi(u_top)) / 2, solved by bisection.
    auto Phi = [](double u) { return 0.5 * std::erfc(-u / std::numbers::sqrt2); };
    const double target = 0.5 * (Phi((bottom - center) / sigma) + Phi((top - center) / sigma));
    double lo = -5.0, hi = 5.0;
    for (int it = 0; it < 200; ++it) {
      const double mid = 0.5 * (lo + hi);
      (Phi(mid) < target ? lo : hi) = mid;
    }
    const double rh50_bin = center + 0.5 * (lo + hi) * sigma;
    // The waveform's bins, each spread evenly over its width, differ from the Gaussian by at
    // most f'/8 per bin: 0.02 bin here.
    EXPECT_NEAR(r.rh_m[50], (center - rh50_bin) * kBinM, 0.05 * kBinM);
    for (int level = 1; level < kRhLevels; ++level) EXPECT_GE(r.rh_m[level], r.rh_m[level - 1]);
  }
}

// Canopy over a strong ground: every group finds the same lowest mode, and the selection keeps
// the default group, a1.
TEST(GediL2aGroups, AllAgreeSoA1IsSelected) {
  const auto values = waveform({{40.0, 200.0, 8.0}, {30.0, 330.0, 5.0}});
  const L2aResult r = process_l2a({values, kAxis, kNoiseMean, kNoiseSd});
  for (const L2aGroupResult& g : r.groups) {
    ASSERT_TRUE(g.has_ground);
    EXPECT_EQ(g.num_detectedmodes, 2);
    EXPECT_NEAR(g.elev_lowestmode_m, elevation(330.0), 1e-6);
  }
  EXPECT_EQ(r.selected_algorithm, 1);
  EXPECT_EQ(&r.selected(), &r.groups[0]);
}

// A weak ground under dense canopy: the ground (A 5.74, sigma 5) smoothed by 6.5 bins peaks at
// 3.5 sigma_n, by 3.5 bins at 4.7. Only groups whose back threshold is under 3.5 (a2: 3, a5: 2)
// carry the signal's end past it and find it as a mode; a1, a3, a4 (6) and a6 (4) end after the
// canopy. The group identifying the lowest non-noise mode is a2 (a5 finds the same, later in
// the order).
TEST(GediL2aGroups, WeakGroundSelectsTheGroupThatSeesIt) {
  const double ground_amplitude = 3.5 * std::hypot(5.0, 6.5) / 5.0;
  const auto values = waveform({{60.0, 200.0, 8.0}, {ground_amplitude, 330.0, 5.0}});
  const L2aResult r = process_l2a({values, kAxis, kNoiseMean, kNoiseSd});
  const bool sees_ground[] = {false, true, false, false, true, false};
  for (int k = 0; k < kL2aGroups; ++k) {
    SCOPED_TRACE(testing::Message() << "a" << k + 1);
    ASSERT_TRUE(r.groups[k].has_ground);
    const double expected = sees_ground[k] ? 330.0 : 200.0;
    EXPECT_NEAR(r.groups[k].lowestmode_bin, expected, 1e-3);
    EXPECT_EQ(r.groups[k].num_detectedmodes, sees_ground[k] ? 2 : 1);
  }
  EXPECT_EQ(r.selected_algorithm, 2);
  EXPECT_NEAR(r.selected().elev_lowestmode_m, elevation(330.0), 1e-3 * kBinM);
  // Over the weak ground the canopy stands rh100 above it: its top crossing, by hand.
  const double top = 200.0 - reach(60.0, 8.0, 6.5, 3.0);
  EXPECT_NEAR(r.selected().rh_m[100], (330.0 - top) * kBinM, 0.05 * kBinM);
}

// Two equal returns (A 20, sigma 3) 12 bins apart: smoothed to sigma S they are two modes only
// when 12 > 2 S. The zero-crossing width 3.5 gives S = 4.61 (two modes), 6.5 gives S = 7.16
// (one, half way). The modes of exp(-(x - 6)^2 / 2S^2) + exp(-(x + 6)^2 / 2S^2) are solved here
// by bisection. a2 (the first 3.5 group) finds the lower mode 6 bins below a1's and is selected.
TEST(GediL2aGroups, ZeroCrossingWidthResolvesCloseModes) {
  const double center = 300.0, half = 6.0;
  const auto values = waveform({{20.0, center - half, 3.0}, {20.0, center + half, 3.0}});
  const L2aResult r = process_l2a({values, kAxis, kNoiseMean, kNoiseSd});
  const double S = std::hypot(3.0, 3.5);
  auto slope = [&](double x) {
    return -(x - half) * std::exp(-0.5 * std::pow((x - half) / S, 2)) -
           (x + half) * std::exp(-0.5 * std::pow((x + half) / S, 2));
  };
  double lo = 0.5, hi = half;  // slope > 0 at lo, < 0 at hi
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    (slope(mid) > 0.0 ? lo : hi) = mid;
  }
  const double lower_mode = center + 0.5 * (lo + hi);
  for (int k = 0; k < kL2aGroups; ++k) {
    SCOPED_TRACE(testing::Message() << "a" << k + 1);
    const bool narrow = kGediL2aGroups[k].zcross_width_bins == 3.5;
    EXPECT_EQ(r.groups[k].num_detectedmodes, narrow ? 2 : 1);
    // The sampled, truncated filter differs from the continuous one by ~1e-4 of the peak.
    EXPECT_NEAR(r.groups[k].lowestmode_bin, narrow ? lower_mode : center, 0.02);
  }
  EXPECT_GT(lower_mode - center, 3.0);  // 0.5 m apart and more: not the same return
  EXPECT_EQ(r.selected_algorithm, 2);
}

// The selection on its own: the lowest ground wins, and among grounds within same_mode_m of it
// the first group in the mission's order.
TEST(GediL2aGroups, SelectionPrefersTheFirstGroupAtTheLowestMode) {
  std::array<L2aGroupResult, kL2aGroups> groups{};
  const double ground_m[] = {100.0, 99.0, 99.3, 0.0, 99.0, 100.0};
  for (int k = 0; k < kL2aGroups; ++k) {
    groups[k].has_ground = k != 3;
    groups[k].elev_lowestmode_m = ground_m[k];  // a4 has none: its 0 must not count
  }
  EXPECT_EQ(select_l2a_group(groups), 1);  // a2: lowest; a3 within 0.5 m but later
  groups[0].elev_lowestmode_m = 99.4;
  EXPECT_EQ(select_l2a_group(groups), 0);  // a1 within 0.5 m of the lowest: the default
  EXPECT_EQ(select_l2a_group(groups, L2aSelection{0.1}), 1);
  for (auto& g : groups) g.has_ground = false;
  EXPECT_EQ(select_l2a_group(groups), -1);
}

TEST(GediL2aGroups, NoSignalNoSelection) {
  const std::vector<double> flat(kBins, kNoiseMean);
  const L2aResult r = process_l2a({flat, kAxis, kNoiseMean, kNoiseSd});
  for (const L2aGroupResult& g : r.groups) {
    EXPECT_FALSE(g.signal);
    EXPECT_TRUE(std::isnan(g.elev_lowestmode_m));
    EXPECT_TRUE(std::isnan(g.rh_m[50]));
  }
  EXPECT_EQ(r.selected_algorithm, 0);
  // No noise level to scale the thresholds by: nothing is processed.
  const auto values = waveform({{50.0, 300.0, 5.0}});
  EXPECT_FALSE(process_l2a_group({values, kAxis, kNoiseMean, 0.0}, kGediL2aGroups[0]).signal);
}

}  // namespace
}  // namespace glaswave
