// Tests of the Gaussian decomposition: synthetic sums of Gaussians with known parameters
// (separate, overlapping, with noise) must come back to 1 % in amplitude and to a small part of a
// bin in centre; components that do not clear the significance level are dropped.
#include "pipeline/products/gaussian_decomposition.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace glaswave {
namespace {

constexpr int kBins = 500;
constexpr double kPulseBins = 5.0;  // the pulse's RMS width: no component narrower

std::vector<double> synthesize(const std::vector<GaussianComponent>& components) {
  std::vector<double> values(kBins, 0.0);
  for (int i = 0; i < kBins; ++i)
    for (const GaussianComponent& g : components) values[i] += g.value_at(i);
  return values;
}

// White noise of RMS `sd` from a fixed test seed: the test data is the same on every run.
void add_noise(std::vector<double>& values, double sd, unsigned seed) {
  std::mt19937_64 engine(seed);
  std::normal_distribution<double> normal(0.0, sd);
  for (double& v : values) v += normal(engine);
}

DecompositionSettings settings(double level) {
  DecompositionSettings s;
  s.min_sigma_bins = kPulseBins;
  s.smooth_sigma_bins = kPulseBins;
  s.significance_level = level;
  return s;
}

// Each expected component against the fitted one in the same place (both sorted by centre):
// amplitude to `amplitude_tolerance` relative, centre and width to the given bins.
void expect_components(const std::vector<GaussianComponent>& fitted,
                       const std::vector<GaussianComponent>& expected, double amplitude_tolerance,
                       double center_tolerance_bins, double sigma_tolerance_bins) {
  ASSERT_EQ(fitted.size(), expected.size());
  for (std::size_t k = 0; k < expected.size(); ++k) {
    EXPECT_NEAR(fitted[k].amplitude / expected[k].amplitude, 1.0, amplitude_tolerance)
        << "component " << k;
    EXPECT_NEAR(fitted[k].center_bin, expected[k].center_bin, center_tolerance_bins)
        << "component " << k;
    EXPECT_NEAR(fitted[k].sigma_bins, expected[k].sigma_bins, sigma_tolerance_bins)
        << "component " << k;
  }
}

TEST(GaussianComponent, AreaIsTheIntegral) {
  const GaussianComponent g{2.0, 100.0, 6.0};
  double sum = 0.0;
  for (int i = 0; i < 200; ++i) sum += g.value_at(i);
  EXPECT_NEAR(g.area(), 2.0 * 6.0 * std::sqrt(2.0 * M_PI), 1e-12);
  EXPECT_NEAR(sum / g.area(), 1.0, 1e-9);  // a bin sum of a Gaussian 6 bins wide is its integral
}

TEST(GaussianSmooth, KeepsAConstantAndTheAreaOfAPeak) {
  const std::vector<double> constant(50, 3.0);
  for (double v : gaussian_smooth(constant, 4.0)) EXPECT_NEAR(v, 3.0, 1e-12);
  // A Gaussian of sigma s through a filter of sigma f: sigma sqrt(s^2 + f^2), same area.
  const std::vector<double> peak = synthesize({{1.0, 250.0, 6.0}});
  const std::vector<double> smoothed = gaussian_smooth(peak, 8.0);
  EXPECT_NEAR(smoothed[250], 6.0 / std::hypot(6.0, 8.0), 1e-4);
}

TEST(GaussianDecomposition, SingleGaussianIsExact) {
  const std::vector<GaussianComponent> truth = {{2.5e-6, 200.3, 6.2}};
  const auto values = synthesize(truth);
  const auto fitted = decompose_waveform(values, 150, 250, settings(0.01 * 2.5e-6));
  expect_components(fitted, truth, 1e-6, 1e-5, 1e-5);
}

TEST(GaussianDecomposition, SeparateGaussiansComeBack) {
  const std::vector<GaussianComponent> truth = {
      {1.0e-6, 120.0, 7.0}, {0.5e-6, 180.4, 5.5}, {0.8e-6, 262.7, 5.0}};
  const auto values = synthesize(truth);
  const auto fitted = decompose_waveform(values, 90, 290, settings(0.01e-6));
  expect_components(fitted, truth, 1e-4, 1e-3, 1e-3);
}

// Pairs closer than the smoothed waveform can show as two peaks: the second is found in the
// residual of a one-Gaussian fit.
TEST(GaussianDecomposition, OverlappingPairsAreResolved) {
  for (const double separation_bins : {16.0, 12.0, 10.0, 8.0, 6.0}) {
    const std::vector<GaussianComponent> truth = {{1.0e-6, 200.0, 5.0},
                                                  {0.7e-6, 200.0 + separation_bins, 6.0}};
    const auto values = synthesize(truth);
    const auto fitted = decompose_waveform(values, 170, 245, settings(0.01e-6));
    SCOPED_TRACE(separation_bins);
    expect_components(fitted, truth, 0.01, 0.05, 0.05);
  }
}

TEST(GaussianDecomposition, CanopyAndGroundWithNoise) {
  // A broad canopy return over a pulse-wide ground return, noise 0.5 % of the peak (SNR 200).
  const std::vector<GaussianComponent> truth = {
      {0.6e-6, 150.0, 14.0}, {0.9e-6, 215.0, 9.0}, {1.0e-6, 300.0, 5.0}};
  int failures = 0;
  double worst_amplitude = 0.0, worst_center = 0.0;
  for (unsigned seed = 1; seed <= 10; ++seed) {
    auto values = synthesize(truth);
    add_noise(values, 0.005e-6, seed);
    const auto fitted = decompose_waveform(values, 100, 330, settings(4.0 * 0.005e-6 / 2.5));
    if (fitted.size() != truth.size()) {
      ++failures;
      continue;
    }
    for (std::size_t k = 0; k < truth.size(); ++k) {
      worst_amplitude =
          std::max(worst_amplitude, std::abs(fitted[k].amplitude / truth[k].amplitude - 1.0));
      worst_center = std::max(worst_center, std::abs(fitted[k].center_bin - truth[k].center_bin));
    }
  }
  EXPECT_EQ(failures, 0);
  EXPECT_LT(worst_amplitude, 0.01);
  EXPECT_LT(worst_center, 0.5);  // 1 % of the canopy's width, 7 cm
}

TEST(GaussianDecomposition, OverlappingPairWithNoise) {
  const std::vector<GaussianComponent> truth = {{1.0e-6, 200.0, 5.0}, {0.7e-6, 214.0, 6.0}};
  for (unsigned seed = 1; seed <= 10; ++seed) {
    auto values = synthesize(truth);
    add_noise(values, 0.002e-6, seed);
    const auto fitted = decompose_waveform(values, 170, 245, settings(4.0 * 0.002e-6 / 2.5));
    SCOPED_TRACE(seed);
    expect_components(fitted, truth, 0.01, 0.2, 0.2);
  }
}

// Known components, one to three, without and with noise, against stated tolerances (bins are
// 1 ns): noise-free, centres within 0.01 ns and widths and areas within 0.1 %; with white
// noise of 0.5 % of the strongest peak (SNR 200, 10 draws), centres within 0.5 ns, widths
// within 5 % and areas within 3 %.
TEST(GaussianDecomposition, KnownComponentsWithinStatedTolerances) {
  const std::vector<std::vector<GaussianComponent>> cases = {
      {{1.0e-6, 210.0, 6.0}},
      {{0.6e-6, 160.0, 9.0}, {1.0e-6, 230.0, 5.0}},
      {{0.5e-6, 130.0, 12.0}, {0.8e-6, 190.0, 7.0}, {1.0e-6, 260.0, 5.0}}};
  for (const auto& truth : cases) {
    for (unsigned seed = 0; seed <= 10; ++seed) {
      auto values = synthesize(truth);
      if (seed > 0) add_noise(values, 0.005e-6, seed);
      const double noise_sd = seed > 0 ? 0.005e-6 / 2.5 : 0.0;  // through the 5-bin filter
      const auto fitted =
          decompose_waveform(values, 80, 300, settings(std::max(4.0 * noise_sd, 0.01e-6)));
      SCOPED_TRACE(testing::Message() << truth.size() << " Gaussians, seed " << seed);
      ASSERT_EQ(fitted.size(), truth.size());
      const double center_ns = seed > 0 ? 0.5 : 0.01, width = seed > 0 ? 0.05 : 0.001,
                   area = seed > 0 ? 0.03 : 0.001;
      for (std::size_t k = 0; k < truth.size(); ++k) {
        EXPECT_NEAR(fitted[k].center_bin, truth[k].center_bin, center_ns) << k;
        EXPECT_NEAR(fitted[k].sigma_bins / truth[k].sigma_bins, 1.0, width) << k;
        EXPECT_NEAR(fitted[k].area() / truth[k].area(), 1.0, area) << k;
      }
    }
  }
}

// A shoulder in its neighbour's flank is no local maximum of the smoothed waveform: the
// curvature finds it from the start.
TEST(GaussianDecomposition, ShoulderFromTheCurvature) {
  const std::vector<GaussianComponent> truth = {{1.0e-6, 200.0, 6.0}, {0.35e-6, 216.0, 5.0}};
  const auto fitted = decompose_waveform(synthesize(truth), 160, 250, settings(0.01e-6));
  expect_components(fitted, truth, 0.01, 0.05, 0.05);
}

TEST(GaussianDecomposition, InsignificantComponentsAreDropped) {
  // A bump whose smoothed peak stays below the level is not a component.
  const std::vector<GaussianComponent> truth = {{1.0e-6, 200.0, 5.0}, {0.004e-6, 280.0, 5.0}};
  const auto values = synthesize(truth);
  const auto fitted = decompose_waveform(values, 170, 300, settings(0.01e-6));
  ASSERT_EQ(fitted.size(), 1u);
  EXPECT_NEAR(fitted[0].center_bin, 200.0, 1e-3);
}

TEST(GaussianDecomposition, NothingAboveTheLevelGivesNothing) {
  const std::vector<double> zeros(kBins, 0.0);
  EXPECT_TRUE(decompose_waveform(zeros, 0, kBins - 1, settings(1e-9)).empty());
}

TEST(GaussianDecomposition, AtMostSixComponents) {
  std::vector<GaussianComponent> truth;
  for (int k = 0; k < 8; ++k) truth.push_back({1.0e-6, 60.0 + 50.0 * k, 5.0});
  const auto fitted = decompose_waveform(synthesize(truth), 0, kBins - 1, settings(0.01e-6));
  EXPECT_EQ(fitted.size(), 6u);
}

TEST(FitGaussians, ConvergesFromAFairGuess) {
  const auto values = synthesize({{1.0, 100.0, 5.0}, {0.5, 118.0, 7.0}});
  const auto fitted = fit_gaussians(values, 70, 150, {{0.8, 98.0, 6.0}, {0.6, 121.0, 5.0}});
  expect_components(fitted, {{1.0, 100.0, 5.0}, {0.5, 118.0, 7.0}}, 1e-6, 1e-6, 1e-6);
}

// A spike narrower than half the pulse is noise, not a return: it is no component.
TEST(GaussianDecomposition, SpikesAreNoComponents) {
  auto values = synthesize({{1.0e-6, 200.0, 5.0}});
  values[300] += 0.3e-6;
  const auto fitted = decompose_waveform(values, 170, 320, settings(0.01e-6));
  ASSERT_EQ(fitted.size(), 1u);
  EXPECT_NEAR(fitted[0].center_bin, 200.0, 1e-3);
}

// Noise that grows with the signal, as a Monte Carlo tally's does: RMS sd0 + sd1 sqrt(v / peak)
// at a value v, drawn white from a fixed seed; `variance` gets each bin's known variance.
std::vector<double> add_known_noise(std::vector<double>& values, double peak, double sd0,
                                    double sd1, unsigned seed) {
  std::mt19937_64 engine(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<double> variance(values.size());
  for (std::size_t i = 0; i < values.size(); ++i) {
    const double sd = sd0 + sd1 * std::sqrt(std::max(values[i], 0.0) / peak);
    variance[i] = sd * sd;
    values[i] += sd * normal(engine);
  }
  return variance;
}

// With each bin's noise known, a component must lower chi^2 by more than chance would (25 for
// 3 parameters, the search over the window included): a broad return under noise of 8 % of its peak
// is one Gaussian in each of 20 draws (centre within 3 bins: the noise's sd over ~100 independent
// bins moves it by ~1), where without the variance the noise's bumps become components of their
// own.
TEST(GaussianDecomposition, NoiseOfKnownVarianceBecomesNoComponent) {
  const std::vector<GaussianComponent> truth = {{1.0e-6, 250.0, 40.0}};
  int split_without_variance = 0;
  for (unsigned seed = 1; seed <= 20; ++seed) {
    auto values = synthesize(truth);
    const std::vector<double> variance = add_known_noise(values, 1.0e-6, 0.005e-6, 0.08e-6, seed);
    DecompositionSettings s = settings(0.01e-6);
    split_without_variance += decompose_waveform(values, 100, 400, s).size() > 1;
    s.error_variance = variance;
    const auto fitted = decompose_waveform(values, 100, 400, s);
    SCOPED_TRACE(seed);
    ASSERT_EQ(fitted.size(), 1u);
    EXPECT_NEAR(fitted[0].center_bin, 250.0, 3.0);
    EXPECT_NEAR(fitted[0].sigma_bins / 40.0, 1.0, 0.1);
  }
  EXPECT_GT(split_without_variance, 0);  // the test would be empty otherwise
}

// Real components stand far above such noise and all stay: canopy, understorey and ground under
// noise of 3 % of the peak, the right number in each of 20 draws.
TEST(GaussianDecomposition, KnownComponentsStayUnderNoiseOfKnownVariance) {
  const std::vector<GaussianComponent> truth = {
      {0.6e-6, 150.0, 14.0}, {0.5e-6, 215.0, 9.0}, {1.0e-6, 300.0, 5.0}};
  for (unsigned seed = 1; seed <= 20; ++seed) {
    auto values = synthesize(truth);
    DecompositionSettings s = settings(0.01e-6);
    const std::vector<double> variance = add_known_noise(values, 1.0e-6, 0.005e-6, 0.03e-6, seed);
    s.error_variance = variance;
    const auto fitted = decompose_waveform(values, 100, 330, s);
    SCOPED_TRACE(seed);
    ASSERT_EQ(fitted.size(), truth.size());
    for (std::size_t k = 0; k < truth.size(); ++k)
      EXPECT_NEAR(fitted[k].center_bin, truth[k].center_bin, 2.0) << k;
  }
}

}  // namespace
}  // namespace glaswave
