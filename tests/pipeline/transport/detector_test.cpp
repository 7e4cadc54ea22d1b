// Tests of the detector model: a constant input gives the expected mean and RMS (detector
// noise, photon statistics), the digitiser keeps 2^bits levels and clips at saturation, the gain
// moves saturation and the step, and the noise is keyed by (seed, shot, band, bin) alone.
#include "pipeline/transport/detector.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <utility>
#include <vector>

namespace glaswave {
namespace {

constexpr double kBinNs = 1.0;
constexpr double kWavelengthNm = 1064.0;
// The energy of a 1064 nm photon, h c / lambda, computed here from CODATA values.
constexpr double kPhotonJ = 6.62607015e-34 * 299792458.0 / 1064e-9;

struct Moments {
  double mean = 0.0, sd = 0.0;
};

Moments moments(const std::vector<double>& values) {
  Moments m;
  for (double v : values) m.mean += v;
  m.mean /= static_cast<double>(values.size());
  for (double v : values) m.sd += (v - m.mean) * (v - m.mean);
  m.sd = std::sqrt(m.sd / static_cast<double>(values.size() - 1));
  return m;
}

Detector::Settings enabled() {
  Detector::Settings s;
  return s;
}

TEST(Detector, WithoutNoiseOrDigitiserTheWaveformPassesUnchanged) {
  const std::vector<double> power = {0.0, 1e-7, 3e-6, 2e-7};
  EXPECT_EQ(Detector(enabled(), 1).record(power, kBinNs, kWavelengthNm, 0, 0), power);
}

// Background plus Gaussian noise on a constant: mean P + background to 4 standard errors,
// RMS to 4 % (20 000 bins: the RMS's standard error is 0.5 %).
TEST(Detector, ConstantInputGivesTheExpectedMeanAndRms) {
  Detector::Settings s = enabled();
  s.background_W = 2e-7;
  s.noise_rms_W = 5e-8;
  const std::vector<double> power(20000, 1e-6);
  const Moments m = moments(Detector(s, 42).record(power, kBinNs, kWavelengthNm, 3, 1));
  EXPECT_NEAR(m.mean, 1.2e-6, 4.0 * 5e-8 / std::sqrt(20000.0));
  EXPECT_NEAR(m.sd / 5e-8, 1.0, 0.04);
}

// Photon statistics: counts per bin are Poisson of mean QE P dt / (h nu); the recorded power's
// variance in photons is mean / QE. Both branches of the Poisson sampler (small and large means).
TEST(Detector, PhotonNoiseIsPoisson) {
  for (const double photons : {3.0, 400.0}) {
    for (const double efficiency : {1.0, 0.5}) {
      Detector::Settings s = enabled();
      s.photon_noise = true;
      s.quantum_efficiency = efficiency;
      const double power_W = photons * kPhotonJ / (kBinNs * 1e-9);
      const std::vector<double> power(20000, power_W);
      const std::vector<double> out = Detector(s, 9).record(power, kBinNs, kWavelengthNm, 0, 0);
      std::vector<double> in_photons;
      for (double w : out) in_photons.push_back(w * kBinNs * 1e-9 / kPhotonJ);
      const Moments m = moments(in_photons);
      const double variance = photons / efficiency;
      SCOPED_TRACE(photons);
      SCOPED_TRACE(efficiency);
      EXPECT_NEAR(m.mean, photons, 4.0 * std::sqrt(variance / 20000.0));
      EXPECT_NEAR(m.sd * m.sd / variance, 1.0, 0.05);
      // Whole photoelectrons.
      for (std::size_t i = 0; i < 20; ++i) {
        const double electrons = in_photons[i] * efficiency;
        EXPECT_NEAR(electrons, std::round(electrons), 1e-6);
      }
    }
  }
}

TEST(Detector, DigitiserHasTwoToTheBitsLevelsAndClipsAtSaturation) {
  Detector::Settings s = enabled();
  s.bits = 4;
  s.saturation_W = 15e-6;  // lsb 1e-6
  std::vector<double> ramp;
  for (int i = 0; i < 2000; ++i) ramp.push_back(-3e-6 + i * 0.0125e-6);  // -3e-6 .. 22e-6
  const std::vector<double> out = Detector(s, 1).record(ramp, kBinNs, kWavelengthNm, 0, 0);
  std::set<double> levels(out.begin(), out.end());
  EXPECT_EQ(levels.size(), 16u);
  EXPECT_EQ(*levels.begin(), 0.0);
  EXPECT_DOUBLE_EQ(*levels.rbegin(), 15e-6);
  for (std::size_t i = 1; i < ramp.size(); ++i) EXPECT_GE(out[i], out[i - 1]) << ramp[i];
  // Each power to the nearest step of 1e-6, negative power to 0, beyond saturation to 15e-6.
  const std::vector<std::pair<double, double>> cases = {
      {-3e-6, 0.0},     {0.49e-6, 0.0},   {0.51e-6, 1e-6},  {3.4e-6, 3e-6}, {3.6e-6, 4e-6},
      {14.4e-6, 14e-6}, {14.6e-6, 15e-6}, {15.4e-6, 15e-6}, {22e-6, 15e-6}, {40e-6, 15e-6}};
  for (const auto& [power_W, expected_W] : cases) {
    const std::vector<double> one =
        Detector(s, 1).record(std::vector<double>{power_W}, kBinNs, kWavelengthNm, 0, 0);
    EXPECT_NEAR(one[0], expected_W, 1e-18) << power_W;
  }
}

TEST(Detector, SaturationWithoutDigitiserClips) {
  Detector::Settings s = enabled();
  s.saturation_W = 2e-6;
  const std::vector<double> out = Detector(s, 1).record(
      std::vector<double>{1e-6, 2e-6, 5e-6, -1e-6}, kBinNs, kWavelengthNm, 0, 0);
  EXPECT_EQ(out, (std::vector<double>{1e-6, 2e-6, 2e-6, -1e-6}));
}

// The digitiser's scale sits after the gain: gain 4 saturates at a quarter of the input power
// and steps a quarter as finely; the product stays in W at the input.
TEST(Detector, GainMovesSaturationAndStep) {
  Detector::Settings s = enabled();
  s.bits = 8;
  s.saturation_W = 255e-6;  // lsb 1e-6 at the digitiser
  s.gain = 4.0;
  const std::vector<double> out = Detector(s, 1).record(
      std::vector<double>{10.1e-6, 10.2e-6, 100e-6}, kBinNs, kWavelengthNm, 0, 0);
  EXPECT_NEAR(out[0], 10.0e-6, 1e-18);   // 40.4 -> 40 steps of 0.25e-6
  EXPECT_NEAR(out[1], 10.25e-6, 1e-18);  // 40.8 -> 41
  EXPECT_NEAR(out[2], 255e-6 / 4.0, 1e-18);
}

TEST(Detector, NoiseIsKeyedBySeedShotBandAndBinAlone) {
  Detector::Settings s = enabled();
  s.noise_rms_W = 1e-7;
  s.background_W = 1e-7;
  s.photon_noise = true;
  const std::vector<double> power(500, 1e-6);
  const Detector detector(s, 5);
  const auto a = detector.record(power, kBinNs, kWavelengthNm, 17, 1);
  EXPECT_EQ(a, detector.record(power, kBinNs, kWavelengthNm, 17, 1));
  // A shorter waveform has the same noise in the bins it has.
  const auto head = detector.record(std::vector<double>(100, 1e-6), kBinNs, kWavelengthNm, 17, 1);
  EXPECT_TRUE(std::equal(head.begin(), head.end(), a.begin()));
  // Another shot, band or seed: other noise (no bin alike).
  for (const auto& other : {detector.record(power, kBinNs, kWavelengthNm, 18, 1),
                            detector.record(power, kBinNs, kWavelengthNm, 17, 0),
                            Detector(s, 6).record(power, kBinNs, kWavelengthNm, 17, 1)}) {
    int same = 0;
    for (std::size_t i = 0; i < a.size(); ++i) same += a[i] == other[i];
    EXPECT_LT(same, 5);
  }
  // Neighbouring bins are uncorrelated.
  const Moments m = moments(a);
  double lag1 = 0.0;
  for (std::size_t i = 1; i < a.size(); ++i) lag1 += (a[i] - m.mean) * (a[i - 1] - m.mean);
  EXPECT_LT(std::abs(lag1 / (a.size() - 1) / (m.sd * m.sd)), 0.15);
}

}  // namespace
}  // namespace glaswave
