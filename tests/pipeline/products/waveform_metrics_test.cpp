// Tests of the waveform metrics on waveforms with known answers: a lone pulse (begin and end
// where its smoothed shape crosses the threshold, rh50 at its centre, no canopy height), a
// uniform block (rh linear), canopy over ground (ground at the lowest Gaussian, CR and GR each
// the energy of its Gaussians), noise (threshold above the noise), and the record-level
// processing with its fill for flagged shots.
#include "pipeline/products/waveform_metrics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace glaswave {
namespace {

constexpr int kBins = 400;
constexpr double kBinNs = 1.0;
constexpr double kPulseNs = 5.0;
constexpr double kBinM = 299792458.0 * kBinNs * 1e-9 / 2.0;  // two-way: 0.1499 m a bin
constexpr double kTopM = 1060.0;                             // elevation of bin 0

const WaveformAxis kAxis{kBinNs, kTopM, kTopM - (kBins - 1) * kBinM};

double elevation(double bin) { return kTopM - bin * kBinM; }

WaveformProcessing noise_free() {
  WaveformProcessing p;
  p.pulse_sigma_ns = kPulseNs;
  p.noise_free = true;
  return p;
}

std::vector<double> gaussians(const std::vector<GaussianComponent>& components) {
  std::vector<double> values(kBins, 0.0);
  for (int i = 0; i < kBins; ++i)
    for (const GaussianComponent& g : components) values[i] += g.value_at(i);
  return values;
}

TEST(WaveformAxis, ElevationIsLinearInTheBin) {
  EXPECT_DOUBLE_EQ(kAxis.elevation_m(0.0, kBins), kTopM);
  EXPECT_NEAR(kAxis.elevation_m(kBins - 1.0, kBins), kAxis.elev_lastbin_m, 1e-9);
  EXPECT_NEAR(kAxis.elevation_m(100.5, kBins), elevation(100.5), 1e-9);
}

// A flat surface: one pulse-wide Gaussian. Seen through the pulse-wide filter it is a Gaussian
// of sqrt(2) pulse widths and 1/sqrt(2) the amplitude, so the 1 %-of-peak threshold is crossed
// sqrt(2) sigma sqrt(2 ln 100) either side of the centre.
TEST(WaveformMetrics, LonePulse) {
  const double center = 250.3, amplitude_W = 2e-6;
  const auto m =
      process_waveform(gaussians({{amplitude_W, center, kPulseNs}}), kAxis, noise_free());
  const double reach_bins = std::sqrt(2.0) * kPulseNs * std::sqrt(2.0 * std::log(100.0));
  // To 0.05 bin (7 mm): the crossing is interpolated linearly on the tail's curve.
  EXPECT_NEAR(m.sig_begin_bin, center - reach_bins, 0.05);
  EXPECT_NEAR(m.sig_end_bin, center + reach_bins, 0.05);
  EXPECT_NEAR(m.sig_begin_m, elevation(center - reach_bins), 0.05 * kBinM);
  EXPECT_NEAR(m.sig_end_m, elevation(center + reach_bins), 0.05 * kBinM);
  EXPECT_NEAR(m.centroid_m, elevation(center), 0.001);
  EXPECT_EQ(m.noise_mean_W, 0.0);
  EXPECT_NEAR(m.threshold_W, 0.01 * amplitude_W / std::sqrt(2.0), 1e-4 * amplitude_W);

  ASSERT_EQ(m.n_peaks, 1);
  EXPECT_NEAR(m.gauss_amp_W[0] / amplitude_W, 1.0, 1e-6);
  EXPECT_NEAR(m.gauss_center_m[0], elevation(center), 1e-5);
  EXPECT_NEAR(m.gauss_sigma_ns[0], kPulseNs, 1e-5);
  const double area_J = amplitude_W * kPulseNs * 1e-9 * std::sqrt(2.0 * std::numbers::pi);
  EXPECT_NEAR(m.gauss_area_J[0] / area_J, 1.0, 1e-6);
  for (int k = 1; k < kMaxGaussians; ++k) {
    EXPECT_TRUE(std::isnan(m.gauss_amp_W[k])) << k;
    EXPECT_TRUE(std::isnan(m.gauss_center_m[k])) << k;
  }

  // The ground is the pulse; the height (signal begin - ground) is the pulse's own rise.
  EXPECT_NEAR(m.ground_elev_m, elevation(center), 1e-5);
  EXPECT_NEAR(m.canopy_height_m, reach_bins * kBinM, 0.05 * kBinM);
  // rh: symmetric about the centre, rh0 and rh100 at the threshold's crossings, reach_bins
  // below and above the ground (the pulse's centre).
  EXPECT_NEAR(m.rh_m[50], 0.0, 0.002);
  EXPECT_NEAR(m.rh_m[0], -reach_bins * kBinM, 0.05 * kBinM);
  EXPECT_NEAR(m.rh_m[100], reach_bins * kBinM, 0.05 * kBinM);
  EXPECT_NEAR(m.rh_m[16], -m.rh_m[84], 0.005);
  for (int k = 1; k < kRhLevels; ++k) EXPECT_GE(m.rh_m[k], m.rh_m[k - 1]) << k;
  // rh84 - rh16 is two sigma of the pulse in metres, nearly (the window cuts the tails).
  EXPECT_NEAR(m.rh_m[84] - m.rh_m[16], 2.0 * kPulseNs * kBinM, 0.02);

  // All ground: TR and GR are the pulse's energy, with only the smoothed reach above 4 sigma
  // in CR.
  EXPECT_NEAR(m.energy_tr_J / area_J, 1.0, 1e-3);
  EXPECT_NEAR(m.energy_gr_J / area_J, 1.0, 1e-3);
  EXPECT_LT(m.energy_cr_J / m.energy_tr_J, 1e-4);
  EXPECT_NEAR(m.waveform_index, -1.0, 2e-4);
}

// A uniform block of 100 bins: the energy grows linearly from its bottom, so rh does too, one
// bin (0.15 m) a percent; rh0 and rh100 are the block's edges.
TEST(WaveformMetrics, UniformBlockHasLinearRh) {
  std::vector<double> values(kBins, 0.0);
  for (int i = 150; i < 250; ++i) values[i] = 1e-6;
  const auto m = process_waveform(values, kAxis, noise_free());
  ASSERT_GE(m.n_peaks, 1);
  const double bottom_m = elevation(249.5), top_m = elevation(149.5);
  for (int k = 0; k <= 100; ++k) {
    const double expected_m = bottom_m + (top_m - bottom_m) * k / 100.0 - m.ground_elev_m;
    EXPECT_NEAR(m.rh_m[k], expected_m, 1e-6) << "rh" << k;
  }
  EXPECT_NEAR(m.energy_tr_J, 100 * 1e-6 * kBinNs * 1e-9, 1e-20);
  EXPECT_NEAR(m.centroid_m, elevation(199.5), 1e-9);
}

// Canopy (a broad return) well above the ground (a pulse): the ground is the lowest Gaussian,
// GR and CR are the energies of the ground's and the canopy's Gaussians, and the canopy height
// reaches the canopy return's upper flank.
TEST(WaveformMetrics, CanopyOverGround) {
  const GaussianComponent canopy{0.8e-6, 150.0, 12.0}, ground{1.2e-6, 300.0, kPulseNs};
  const auto m = process_waveform(gaussians({canopy, ground}), kAxis, noise_free());
  ASSERT_EQ(m.n_peaks, 2);
  EXPECT_NEAR(m.gauss_center_m[0], elevation(150.0), 1e-4);
  EXPECT_NEAR(m.gauss_center_m[1], elevation(300.0), 1e-4);
  EXPECT_NEAR(m.ground_elev_m, elevation(300.0), 1e-4);
  const double to_J = kBinNs * 1e-9;
  EXPECT_NEAR(m.energy_gr_J / (ground.area() * to_J), 1.0, 1e-3);
  EXPECT_NEAR(m.energy_cr_J / (canopy.area() * to_J), 1.0, 5e-3);  // less the tails beyond begin
  EXPECT_NEAR(m.energy_tr_J / ((canopy.area() + ground.area()) * to_J), 1.0, 5e-3);
  EXPECT_NEAR(m.waveform_index, (canopy.area() - ground.area()) / (canopy.area() + ground.area()),
              5e-3);
  // Signal begin: where the smoothed canopy (12 and 5 -> 13 bins wide) crosses 1 % of the
  // smoothed peak, which is the ground's (1.2e-6 / sqrt 2 = 0.85e-6 against 0.8e-6 * 12 / 13).
  const double smoothed_ground = 1.2e-6 / std::sqrt(2.0), canopy_sigma = std::hypot(12.0, kPulseNs);
  const double smoothed_canopy = 0.8e-6 * 12.0 / canopy_sigma;
  const double begin =
      150.0 - canopy_sigma * std::sqrt(2.0 * std::log(smoothed_canopy / (0.01 * smoothed_ground)));
  EXPECT_NEAR(m.sig_begin_bin, begin, 0.05);
  // Height: signal begin above the ground (the ground Gaussian's centre at bin 300), = rh100.
  EXPECT_NEAR(m.canopy_height_m, (300.0 - begin) * kBinM, 0.01);
  EXPECT_NEAR(m.rh_m[100], (300.0 - begin) * kBinM, 0.01);  // rh100 goes through the bin axis
}

// With noise: the threshold sits 4 noise sigmas (of the smoothed waveform) over the noise mean,
// which comes from the quiet end of the window; the noise mean is taken out of the energies.
TEST(WaveformMetrics, ThresholdAboveTheNoise) {
  const double background_W = 0.05e-6, noise_W = 0.01e-6;
  auto values = gaussians({{1.0e-6, 200.0, kPulseNs}});
  std::mt19937_64 engine(7);
  std::normal_distribution<double> normal(0.0, noise_W);
  for (double& v : values) v += background_W + normal(engine);
  WaveformProcessing processing = noise_free();
  processing.noise_free = false;
  const auto m = process_waveform(values, kAxis, processing);
  EXPECT_NEAR(m.noise_mean_W, background_W, 3.0 * noise_W / std::sqrt(60.0));
  // White noise through a Gaussian filter of s bins keeps 1 / sqrt(2 sqrt(pi) s) of its RMS.
  const double smoothed_sd = noise_W / std::sqrt(2.0 * std::sqrt(std::numbers::pi) * kPulseNs);
  EXPECT_NEAR(m.noise_sd_W / smoothed_sd, 1.0, 0.2);
  const double reach =
      std::sqrt(2.0) * kPulseNs *
      std::sqrt(2.0 * std::log(1.0e-6 / std::sqrt(2.0) / (m.threshold_W - m.noise_mean_W)));
  EXPECT_NEAR(m.sig_begin_bin, 200.0 - reach, 1.0);
  EXPECT_NEAR(m.sig_end_bin, 200.0 + reach, 1.0);
  ASSERT_EQ(m.n_peaks, 1);
  EXPECT_NEAR(m.ground_elev_m, elevation(200.0), 0.02);
  EXPECT_NEAR(m.gauss_amp_W[0] / 1e-6, 1.0, 0.02);
  EXPECT_NEAR(m.canopy_height_m, reach * kBinM, 1.0 * kBinM);  // the pulse's rise over the noise
  EXPECT_NEAR(m.rh_m[50], 0.0, 0.05);
  const double area_J = 1.0e-6 * kPulseNs * 1e-9 * std::sqrt(2.0 * std::numbers::pi);
  EXPECT_NEAR(m.energy_tr_J / area_J, 1.0, 0.03);
  // Signal begin (about 21 bins above the centre) barely reaches past the split 4 sigma
  // (20 bins) above it: nearly all of TR is ground.
  EXPECT_NEAR(m.energy_gr_J / area_J, 1.0, 0.03);
}

// The threshold on a window whose noise is known exactly: +-a alternating about the background
// (mean the background, sample sd a sqrt(60/59) over the 15 % = 60 bins of an end), so it must
// sit 4 sd of the smoothed noise above the background: GLA14's rule, the white-noise gain of a
// Gaussian filter of s bins 1 / sqrt(2 sqrt(pi) s) (the sum of its squared weights, to 4e-5).
// 4 sd (0.0096e-6 W) is above 1 % of the smoothed peak (0.0071e-6 W), which does not decide.
TEST(WaveformMetrics, ThresholdIsFourSmoothedNoiseSigmasAboveTheBackground) {
  const double background_W = 0.05e-6, a_W = 0.01e-6;
  auto values = gaussians({{1.0e-6, 200.0, kPulseNs}});
  for (int i = 0; i < kBins; ++i) values[i] += background_W + (i % 2 == 0 ? a_W : -a_W);
  WaveformProcessing processing = noise_free();
  processing.noise_free = false;
  const auto m = process_waveform(values, kAxis, processing);
  const double sample_sd = a_W * std::sqrt(60.0 / 59.0);
  const double smoothed_sd = sample_sd / std::sqrt(2.0 * std::sqrt(std::numbers::pi) * kPulseNs);
  EXPECT_NEAR(m.threshold_W / (background_W + 4.0 * smoothed_sd), 1.0, 1e-4);
  EXPECT_GT(4.0 * smoothed_sd, 0.01 * 1.0e-6 / std::sqrt(2.0));
}

TEST(WaveformMetrics, NoSignal) {
  const auto m = process_waveform(std::vector<double>(kBins, 0.0), kAxis, noise_free());
  EXPECT_EQ(m.n_peaks, 0);
  EXPECT_EQ(m.energy_tr_J, 0.0);
  EXPECT_EQ(m.energy_gr_J, 0.0);
  EXPECT_TRUE(std::isnan(m.sig_begin_m));
  EXPECT_TRUE(std::isnan(m.ground_elev_m));
  EXPECT_TRUE(std::isnan(m.canopy_height_m));
  EXPECT_TRUE(std::isnan(m.waveform_index));
  EXPECT_TRUE(std::isnan(m.rh_m[50]));
  const auto fill = process_waveform(std::vector<double>(kBins, std::nan("")), kAxis, noise_free());
  EXPECT_EQ(fill.n_peaks, 0);
  EXPECT_TRUE(std::isnan(fill.energy_tr_J));
}

// A shot none of whose bands rises above its threshold is flagged "no signal"; one whose best
// peak stands under 8 detector-noise sd above the noise, "low signal"; a clear one stays valid.
TEST(ProcessShotWaveforms, NoSignalAndLowSignalAreFlagged) {
  auto shot = [](const std::vector<std::vector<double>>& waveforms) {
    ShotRecord record;
    record.elev_bin0_m = kAxis.elev_bin0_m;
    record.elev_lastbin_m = kAxis.elev_lastbin_m;
    record.rx_waveform_W = waveforms;
    return record;
  };
  ShotRecord empty = shot({std::vector<double>(kBins, 0.0), std::vector<double>(kBins, 0.0)});
  process_shot_waveforms(empty, kBinNs, noise_free());
  EXPECT_EQ(empty.quality_flag, quality_invalid);
  EXPECT_EQ(empty.quality_reason, reason_no_signal);

  // Noise of 0.01e-6 W RMS is 0.0024e-6 W through the 5-bin filter: a pulse of 0.04e-6 W
  // (0.028e-6 smoothed, 12 sd) is clear, one of 0.02e-6 W (6 sd) is above the 4-sd threshold
  // but low.
  const double noise_W = 0.01e-6;
  auto noisy = [&](double amplitude_W, unsigned seed) {
    auto values = gaussians({{amplitude_W, 200.0, kPulseNs}});
    std::mt19937_64 engine(seed);
    std::normal_distribution<double> normal(0.0, noise_W);
    for (double& v : values) v += normal(engine);
    return values;
  };
  WaveformProcessing detected = noise_free();
  detected.noise_free = false;
  ShotRecord low = shot({noisy(0.02e-6, 3), std::vector<double>(kBins, 0.0)});
  process_shot_waveforms(low, kBinNs, detected);
  EXPECT_EQ(low.quality_flag, quality_invalid);
  EXPECT_EQ(low.quality_reason, reason_low_signal);
  EXPECT_EQ(low.n_peaks[0], 1) << "the metrics stay";

  ShotRecord clear = shot({noisy(0.02e-6, 3), noisy(0.04e-6, 4)});
  process_shot_waveforms(clear, kBinNs, detected);
  EXPECT_EQ(clear.quality_flag, quality_good) << "one clear band makes the shot valid";
  EXPECT_EQ(clear.quality_reason, reason_none);
}

TEST(ProcessShotWaveforms, FillsEveryBandAndFillsFlaggedShots) {
  ShotRecord record;
  record.elev_bin0_m = kAxis.elev_bin0_m;
  record.elev_lastbin_m = kAxis.elev_lastbin_m;
  record.rx_waveform_W = {gaussians({{1e-6, 250.0, kPulseNs}}),
                          gaussians({{2e-6, 240.0, kPulseNs}})};
  const auto noise = process_shot_waveforms(record, kBinNs, noise_free());
  EXPECT_EQ(noise, (std::vector<double>{0.0, 0.0}));
  ASSERT_EQ(record.energy_tr_J.size(), 2u);
  ASSERT_EQ(record.n_peaks, (std::vector<std::int32_t>{1, 1}));
  EXPECT_NEAR(record.ground_elev_est_m[0], elevation(250.0), 1e-4);
  EXPECT_NEAR(record.ground_elev_est_m[1], elevation(240.0), 1e-4);
  ASSERT_EQ(record.gauss_amp_W.size(), 2u);
  EXPECT_EQ(record.gauss_amp_W[1].size(), static_cast<std::size_t>(kMaxGaussians));
  ASSERT_EQ(record.rh_m.size(), 2u);
  EXPECT_EQ(record.rh_m[0].size(), static_cast<std::size_t>(kRhLevels));
  EXPECT_NEAR(record.rh_m[1][50], 0.0, 0.002);

  record.quality_flag = quality_invalid;
  process_shot_waveforms(record, kBinNs, noise_free());
  EXPECT_EQ(record.n_peaks, (std::vector<std::int32_t>{0, 0}));
  EXPECT_TRUE(std::isnan(record.energy_tr_J[1]));
  EXPECT_TRUE(std::isnan(record.rh_m[0][98]));
  EXPECT_TRUE(std::isnan(record.gauss_center_m[0][0]));
}

// signal_quality and process_waveform's signal against the header's rule worked out by hand,
// not against each other (both share the threshold): with the smoothed peak P over the noise
// mean, the threshold mean + max(4 sd, 1 % of P) is crossed exactly when P > 4 sd and P > 0,
// and the signal is low while P < 8 sd. The inputs' P and sd are known in closed form:
// - a Gaussian of amplitude A and sigma s smoothed by the pulse's Gaussian (sigma s, unit sum)
//   peaks at A s / sqrt(s^2 + s^2) = A / sqrt(2) (the discrete sums equal the integrals to 4e-5);
// - +-a alternating over the window has mean 0 and sample sd a sqrt(60/59) over an end's 60
//   bins; through the filter, as white noise: sd = a sqrt(60/59) / sqrt(2 sqrt(pi) s). The
//   filter leaves the alternation ~2e-5 a in the middle, under 0.08 a at the window's ends (the
//   kernel cut there), far under every pulse below (>= 3.5 sd = 0.84 a).
// Pulses at 3.5, 4.5, 7.5 and 8.5 sd fall 0.5 sd (6 to 12 %) either side of the 4 and 8 sd
// bounds, so a threshold or a noise level off by that much changes an answer.
TEST(SignalQuality, FollowsTheThresholdRuleWorkedByHand) {
  using Q = SignalQuality;
  WaveformProcessing detected = noise_free();
  detected.noise_free = false;
  const double a_W = 0.01e-6;
  const double smoothed_sd_W =
      a_W * std::sqrt(60.0 / 59.0) / std::sqrt(2.0 * std::sqrt(std::numbers::pi) * kPulseNs);
  auto pulse_over_noise = [&](double peak_sds) {
    auto values = gaussians({{peak_sds * smoothed_sd_W * std::sqrt(2.0), 200.0, kPulseNs}});
    for (int i = 0; i < kBins; ++i) values[i] += i % 2 == 0 ? a_W : -a_W;
    return values;
  };
  std::vector<double> one_bin(kBins, 0.0), one_bin_and_negative(kBins, 0.0);
  one_bin[3] = one_bin_and_negative[3] = 1e-9;
  // Smoothed, bin i holds (e^(-(i-3)^2/50) - 2 e^(-(i-5)^2/50)) 1e-9 / sum: negative wherever the
  // kernel reaches (positive only for i < -4.7), 0 beyond: P = 0, no signal.
  one_bin_and_negative[5] = -2e-9;
  // A pulse on a negative floor -b. Noise-free, no noise is measured (mean 0, sd 0): P = A/sqrt(2)
  // - b. Detected, the floor is the noise mean (sd 0): P = A/sqrt(2), signal whatever b is.
  auto pulse_on_floor = [&](double peak_over_floor) {
    const double floor_W = 1e-8;
    auto values = gaussians({{peak_over_floor * floor_W * std::sqrt(2.0), 200.0, kPulseNs}});
    for (double& v : values) v -= floor_W;
    return values;
  };
  struct Case {
    const char* name;
    std::vector<double> power_W;
    Q noise_free, detected;  // expected with each setting
  };
  const std::vector<Case> cases = {
      {"zeros", std::vector<double>(kBins, 0.0), Q::none, Q::none},  // P = 0, sd = 0
      {"fill", std::vector<double>(kBins, std::nan("")), Q::none, Q::none},
      {"two bins", std::vector<double>(2, 1.0), Q::none, Q::none},  // under 3 bins: none
      // Nothing at the ends (detected, sd 0 or under 1e-170 W): any P > 0 is signal, and good.
      {"1e-6 W pulse", gaussians({{1e-6, 200.0, kPulseNs}}), Q::good, Q::good},
      {"1e-300 W pulse", gaussians({{1e-300, 200.0, kPulseNs}}), Q::good, Q::good},
      // Detected, the head holds the bin (mean 1e-9/60): the tail is the quieter end, mean 0.
      {"one bin of 1e-9 W", one_bin, Q::good, Q::good},
      // Detected, the head is the quieter end (mean -1e-9/60, sample sd 2.9e-10, 6.9e-11 smoothed):
      // P = 0 + 1e-9/60 is under 4 sd.
      {"one bin and a negative one", one_bin_and_negative, Q::none, Q::none},
      {"pulse 1.2 x the floor", pulse_on_floor(1.2), Q::good, Q::good},
      {"pulse 0.8 x the floor", pulse_on_floor(0.8), Q::none, Q::good},
  };
  for (const Case& c : cases)
    for (const WaveformProcessing& settings : {noise_free(), detected}) {
      const Q expected = settings.noise_free ? c.noise_free : c.detected;
      const char* mode = settings.noise_free ? ", noise-free" : ", detected";
      EXPECT_EQ(signal_quality(c.power_W, kAxis, settings), expected) << c.name << mode;
      EXPECT_EQ(process_waveform(c.power_W, kAxis, settings).signal, expected) << c.name << mode;
    }
  // Against the noise (detected only: noise-free, the alternation smoothed is above 0 somewhere).
  const std::vector<std::pair<double, Q>> noisy = {
      {0.0, Q::none}, {3.5, Q::none}, {4.5, Q::low}, {7.5, Q::low}, {8.5, Q::good}};
  for (const auto& [peak_sds, expected] : noisy) {
    const auto values = pulse_over_noise(peak_sds);
    EXPECT_EQ(signal_quality(values, kAxis, detected), expected) << peak_sds << " sd";
    EXPECT_EQ(process_waveform(values, kAxis, detected).signal, expected) << peak_sds << " sd";
  }
}

// flag_shot_signal flags as process_shot_waveforms does (a second path to the same flag: it only
// asks signal_quality) and leaves the metrics fill; where a shot's flag is known without either
// (no light at all, a clean pulse, noise alone), it is checked against that too.
TEST(FlagShotSignal, FlagsAsTheProcessingAndLeavesTheMetricsFill) {
  WaveformProcessing detected = noise_free();
  detected.noise_free = false;
  std::mt19937_64 engine(5);
  std::normal_distribution<double> normal(0.0, 0.01e-6);
  auto noisy = [&](double amplitude_W) {
    auto values = gaussians({{amplitude_W, 200.0, kPulseNs}});
    for (double& v : values) v += normal(engine);
    return values;
  };
  const std::vector<std::vector<std::vector<double>>> shots = {
      {std::vector<double>(kBins, 0.0), std::vector<double>(kBins, 0.0)},
      {gaussians({{1e-6, 250.0, kPulseNs}}), std::vector<double>(kBins, 0.0)},
      {noisy(0.02e-6), noisy(0.0)},
      {noisy(0.02e-6), noisy(0.04e-6)},
      {noisy(0.0), noisy(0.0)}};
  for (const WaveformProcessing& settings : {noise_free(), detected})
    for (std::size_t k = 0; k < shots.size(); ++k) {
      ShotRecord processed;
      processed.elev_bin0_m = kAxis.elev_bin0_m;
      processed.elev_lastbin_m = kAxis.elev_lastbin_m;
      processed.rx_waveform_W = shots[k];
      ShotRecord flagged = processed;
      process_shot_waveforms(processed, kBinNs, settings);
      flag_shot_signal(flagged, kBinNs, settings);
      EXPECT_EQ(flagged.quality_flag, processed.quality_flag) << "shot " << k;
      EXPECT_EQ(flagged.quality_reason, processed.quality_reason) << "shot " << k;
      // Known by construction: no light in either band has no signal; a 1 uW pulse on no noise
      // is a good shot; detected, noise alone (no pulse in either band) has no signal.
      if (k == 0 || (k == 4 && !settings.noise_free)) {
        EXPECT_EQ(flagged.quality_flag, quality_invalid) << "shot " << k;
        EXPECT_EQ(flagged.quality_reason, reason_no_signal) << "shot " << k;
      }
      if (k == 1) EXPECT_EQ(flagged.quality_flag, quality_good) << "shot " << k;
      ASSERT_EQ(flagged.n_peaks, (std::vector<std::int32_t>{0, 0}));
      EXPECT_TRUE(std::isnan(flagged.energy_tr_J[0]));
      EXPECT_TRUE(std::isnan(flagged.rh_m[1][50]));
    }
}

}  // namespace
}  // namespace glaswave
