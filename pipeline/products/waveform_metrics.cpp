// Waveform metrics: threshold, extent, decomposition, partition and relative heights of one
// waveform. The rules are set out in the header.
#include "pipeline/products/waveform_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "pipeline/products/canopy_indices.hpp"
#include "pipeline/products/product_fields.hpp"

namespace glaswave {
namespace {

constexpr double nan = std::numeric_limits<double>::quiet_NaN();
// Split between canopy and ground: this many sigma of the ground Gaussian above its centre
// holds all but 3e-5 of the ground's energy.
constexpr double kSplitSigmas = 4.0;
// A ground Gaussian's amplitude is at least this part of the strongest Gaussian's.
constexpr double kGroundMinAmplitude = 0.02;

struct Statistics {
  double mean = 0.0, sd = 0.0;
};

Statistics statistics(std::span<const double> values) {
  Statistics s;
  if (values.empty()) return s;
  for (double v : values) s.mean += v;
  s.mean /= static_cast<double>(values.size());
  double squares = 0.0;
  for (double v : values) squares += (v - s.mean) * (v - s.mean);
  s.sd = values.size() > 1 ? std::sqrt(squares / static_cast<double>(values.size() - 1)) : 0.0;
  return s;
}

// What a Gaussian filter of sigma_bins (as gaussian_smooth applies it) leaves of the RMS of
// white noise: sqrt of the sum of its squared weights. The noise's RMS is measured on the raw
// waveform and scaled by this, since the RMS of a few dozen smoothed bins, correlated over
// several bins, comes out far too low.
double filter_noise_gain(double sigma_bins) {
  const int half = std::max(1, static_cast<int>(std::ceil(4.0 * sigma_bins)));
  double sum = 0.0, squares = 0.0;
  for (int k = -half; k <= half; ++k) {
    const double w = std::exp(-0.5 * (k / sigma_bins) * (k / sigma_bins));
    sum += w;
    squares += w * w;
  }
  return std::sqrt(squares) / sum;
}

// What the decomposition's test weighs each bin's misfit by: the detector's noise, white, and
// the Monte Carlo noise, which the pulse spreads over its neighbours: correlated over the
// pulse (autocorrelation exp(-m^2 / 4 sigma^2) for a Gaussian pulse of sigma bins), it counts
// sum_m exp(-m^2 / 2 sigma^2) ~ sqrt(2 pi) sigma times its variance. Empty when there is no
// noise at all (a noise-free waveform without its Monte Carlo variance).
std::vector<double> error_variance(std::span<const double> mc_variance_W2, double detector_sd_W,
                                   double pulse_bins, std::size_t bins) {
  double correlation_bins = 0.0;
  const int reach = static_cast<int>(std::ceil(6.0 * pulse_bins));
  for (int m = -reach; m <= reach; ++m)
    correlation_bins += std::exp(-0.5 * m * m / (pulse_bins * pulse_bins));
  std::vector<double> variance(bins, detector_sd_W * detector_sd_W);
  if (mc_variance_W2.size() == bins)
    for (std::size_t i = 0; i < bins; ++i) variance[i] += correlation_bins * mc_variance_W2[i];
  const double largest = *std::max_element(variance.begin(), variance.end());
  if (!(largest > 0.0) || !std::isfinite(largest)) return {};
  return variance;
}

// The part of bin i ([i - 0.5, i + 0.5]) that lies in [a, b].
double overlap(int i, double a, double b) {
  return std::max(0.0, std::min(i + 0.5, b) - std::max(i - 0.5, a));
}

// Noise level from the quieter end of the window: the return sits inside it, but tall canopy
// on steep ground may reach one end. The sd is that of the smoothed waveform.
Statistics measure_noise(std::span<const double> power_W, const WaveformProcessing& settings,
                         double pulse_bins) {
  Statistics noise;
  if (settings.noise_free) return noise;
  const int n = static_cast<int>(power_W.size());
  const int end_bins = std::clamp(static_cast<int>(settings.noise_fraction * n), 2, n);
  const Statistics head = statistics(power_W.subspan(0, end_bins));
  const Statistics tail = statistics(power_W.subspan(n - end_bins));
  const bool use_head = head.mean <= tail.mean;
  noise.mean = use_head ? head.mean : tail.mean;
  noise.sd = (use_head ? head.sd : tail.sd) * filter_noise_gain(pulse_bins);
  return noise;
}

// Signal begin and end (fractional bins): the first and last crossings of the threshold,
// interpolated between bins. The smoothed waveform must exceed the threshold somewhere.
struct Extent {
  double begin = 0.0, end = 0.0;
};

Extent signal_extent(const std::vector<double>& smoothed, double threshold) {
  const ThresholdCrossings c = threshold_crossings(smoothed, threshold, threshold);
  return {c.begin_bin, c.end_bin};
}

// The Gaussians fitted over the signal's extent and the pulse's tails beyond it, and their
// slots in the metrics as elevations, times and energies.
void decompose(const std::vector<double>& signal, std::span<const double> variance, Extent extent,
               double pulse_bins, double significance_level, const WaveformProcessing& settings,
               const WaveformAxis& axis, WaveformMetrics& m) {
  const std::size_t bins = signal.size();
  DecompositionSettings decomposition;
  decomposition.max_components = kMaxGaussians;
  decomposition.min_sigma_bins = pulse_bins;
  decomposition.smooth_sigma_bins = pulse_bins;
  decomposition.significance_level = significance_level;
  decomposition.min_area_fraction = settings.min_gaussian_area_fraction;
  decomposition.error_variance = variance;
  const int margin = static_cast<int>(std::ceil(3.0 * pulse_bins));
  m.gaussians = decompose_waveform(signal, static_cast<int>(std::floor(extent.begin)) - margin,
                                   static_cast<int>(std::ceil(extent.end)) + margin, decomposition);
  m.n_peaks = static_cast<int>(m.gaussians.size());
  for (int k = 0; k < m.n_peaks && k < kMaxGaussians; ++k) {
    const GaussianComponent& g = m.gaussians[k];
    m.gauss_amp_W[k] = g.amplitude;
    m.gauss_center_m[k] = axis.elevation_m(g.center_bin, bins);
    m.gauss_sigma_ns[k] = g.sigma_bins * axis.bin_ns;
    m.gauss_area_J[k] = g.area() * axis.bin_ns * 1e-9;
  }
}

// The ground (m.ground_elev_m) and the split between canopy and ground, as a fractional bin
// (larger is lower), from at least one Gaussian. The ground is the lowest Gaussian that is a
// peak of its own, as strong as a surface return is. Light scattered many times in the crowns
// arrives late and trails below the ground as a faint, broad tail, which a fit covers with a
// broad Gaussian of a few % of the peak; a ground return, pulse-wide, stands far higher even
// under dense crowns.
double split_at_ground(const WaveformAxis& axis, std::size_t bins, WaveformMetrics& m) {
  double strongest = 0.0;
  for (const GaussianComponent& g : m.gaussians) strongest = std::max(strongest, g.amplitude);
  auto strong = [&](std::size_t k) {
    return m.gaussians[k].amplitude >= kGroundMinAmplitude * strongest;
  };
  // A peak of its own: the fitted waveform is no higher half its width above or below its
  // centre. A broad tail under a return above it, however strong, is none.
  auto own_peak = [&](std::size_t k) {
    const GaussianComponent& g = m.gaussians[k];
    auto model = [&](double x) {
      double sum = 0.0;
      for (const GaussianComponent& other : m.gaussians) sum += other.value_at(x);
      return sum;
    };
    const double top = model(g.center_bin);
    return top >= model(g.center_bin - 0.5 * g.sigma_bins) &&
           top >= model(g.center_bin + 0.5 * g.sigma_bins);
  };
  std::size_t ground_index = m.gaussians.size() - 1;
  while (ground_index > 0 && !(strong(ground_index) && own_peak(ground_index))) --ground_index;
  if (!(strong(ground_index) && own_peak(ground_index))) {
    // None is a peak of its own (a ground in the canopy's flank): the lowest strong one.
    ground_index = m.gaussians.size() - 1;
    while (ground_index > 0 && !strong(ground_index)) --ground_index;
  }
  const GaussianComponent& ground = m.gaussians[ground_index];
  m.ground_elev_m = axis.elevation_m(ground.center_bin, bins);
  double split = ground.center_bin - kSplitSigmas * ground.sigma_bins;
  // Where the canopy's Gaussians outweigh the ground's before that, the split comes down (with
  // none above the ground, nothing can: a broad ground spans thousands of steps).
  for (double x = ground.center_bin; ground_index > 0 && x > split; x -= 0.05) {
    double others = 0.0;
    for (std::size_t k = 0; k < ground_index; ++k) others += m.gaussians[k].value_at(x);
    if (others > ground.value_at(x)) {
      split = x;
      break;
    }
  }
  return split;
}

// The signal's energy between begin and end, by part of each bin, above and below the split.
struct Partition {
  double canopy = 0.0, ground = 0.0, moment = 0.0;
  std::vector<double> energy;  // per bin, within [begin, end]
};

Partition partition_energy(const std::vector<double>& signal, Extent extent, double split) {
  const int n = static_cast<int>(signal.size());
  const double begin = extent.begin, end = extent.end;
  Partition p;
  p.energy.assign(n, 0.0);
  for (int i = static_cast<int>(std::floor(begin)); i <= static_cast<int>(std::ceil(end)) && i < n;
       ++i) {
    if (i < 0) continue;
    p.energy[i] = signal[i] * overlap(i, begin, end);
    p.moment += p.energy[i] * i;
    p.canopy += signal[i] * overlap(i, begin, std::min(split, end));
    p.ground += signal[i] * overlap(i, std::max(split, begin), end);
  }
  return p;
}

// rh: counted up from signal end (cumulative_energy_bins), above the ground; `total` > 0 is the
// energy between begin and end.
void relative_heights(const std::vector<double>& energy, double total, Extent extent,
                      const WaveformAxis& axis, WaveformMetrics& m) {
  const std::size_t n = energy.size();
  const std::array<double, kRhLevels> position =
      cumulative_energy_bins(energy, total, extent.begin, extent.end);
  for (int k = 0; k < kRhLevels; ++k)
    m.rh_m[k] = axis.elevation_m(position[k], n) - m.ground_elev_m;
}

// TR, CR, GR, the waveform index, the centroid, rh and the canopy height from the partition.
// Without a Gaussian there is no ground to split at: CR and GR are NaN, and so is what
// needs the ground.
void store_partition(const Partition& p, Extent extent, const WaveformAxis& axis,
                     WaveformMetrics& m) {
  const std::size_t bins = p.energy.size();
  const double joules_per_bin = axis.bin_ns * 1e-9;
  const double total = p.canopy + p.ground;
  if (total > 0.0) m.centroid_m = axis.elevation_m(p.moment / total, bins);
  if (m.gaussians.empty()) {
    m.energy_tr_J = total * joules_per_bin;
    m.energy_cr_J = m.energy_gr_J = nan;
    return;
  }
  m.energy_cr_J = p.canopy * joules_per_bin;
  m.energy_gr_J = p.ground * joules_per_bin;
  m.energy_tr_J = m.energy_cr_J + m.energy_gr_J;
  m.waveform_index = waveform_index(m.energy_cr_J, m.energy_gr_J);  // NaN (none()) when TR is 0
  if (total > 0.0) relative_heights(p.energy, total, extent, axis, m);
  // Canopy height as the product contract and GLA14 define it: signal begin above the ground.
  // It includes the pulse's own rise to the threshold (about 3 m for a 5 ns pulse over bare
  // ground with no noise), as the instrument's products do.
  m.canopy_height_m = m.sig_begin_m - m.ground_elev_m;
}

}  // namespace

namespace {

// A shot none of whose bands has signal is flagged "no signal"; one whose best is low, "low
// signal".
void flag_signal(ShotRecord& record, std::size_t bands, SignalQuality best) {
  if (bands > 0 && best != SignalQuality::good) {
    record.quality_flag = quality_invalid;
    record.quality_reason = best == SignalQuality::none ? reason_no_signal : reason_low_signal;
  }
}

}  // namespace

double WaveformAxis::elevation_m(double bin, std::size_t bins) const {
  if (bins < 2) return elev_bin0_m;
  return elev_bin0_m + (elev_lastbin_m - elev_bin0_m) * bin / static_cast<double>(bins - 1);
}

WaveformMetrics WaveformMetrics::none() {
  WaveformMetrics m;
  m.noise_mean_W = m.noise_sd_W = m.threshold_W = nan;
  m.energy_tr_J = m.energy_cr_J = m.energy_gr_J = m.waveform_index = nan;
  m.sig_begin_m = m.sig_end_m = m.centroid_m = nan;
  m.sig_begin_bin = m.sig_end_bin = nan;
  m.n_peaks = 0;
  m.gauss_amp_W.fill(nan);
  m.gauss_center_m.fill(nan);
  m.gauss_sigma_ns.fill(nan);
  m.gauss_area_J.fill(nan);
  m.ground_elev_m = m.canopy_height_m = nan;
  m.rh_m.fill(nan);
  return m;
}

namespace {

// Whether a waveform can be processed at all: at least 3 bins of a width, every value finite.
bool processable(std::span<const double> power_W, const WaveformAxis& axis) {
  if (power_W.size() < 3 || !(axis.bin_ns > 0.0)) return false;
  for (double p : power_W)
    if (!std::isfinite(p)) return false;
  return true;
}

// The smoothed waveform, its noise and its threshold: the first steps of the processing, which
// decide the signal's quality.
struct Threshold {
  std::vector<double> smoothed;
  Statistics noise;
  double above = 0.0;  // the threshold above the noise mean
  double threshold_W = 0.0;
  SignalQuality signal = SignalQuality::none;
};

Threshold threshold_of(std::span<const double> power_W, const WaveformAxis& axis,
                       const WaveformProcessing& settings) {
  Threshold t;
  const double pulse_bins = settings.pulse_sigma_ns / axis.bin_ns;
  t.smoothed = gaussian_smooth(power_W, pulse_bins);
  t.noise = measure_noise(power_W, settings, pulse_bins);
  const double peak = *std::max_element(t.smoothed.begin(), t.smoothed.end());
  t.above =
      std::max(settings.noise_sigmas * t.noise.sd, settings.peak_fraction * (peak - t.noise.mean));
  t.threshold_W = t.noise.mean + t.above;
  if (!(peak > t.threshold_W) || !(t.above > 0.0)) return t;  // no signal
  t.signal = peak - t.noise.mean < settings.low_signal_sigmas * t.noise.sd ? SignalQuality::low
                                                                           : SignalQuality::good;
  return t;
}

}  // namespace

SignalQuality signal_quality(std::span<const double> power_W, const WaveformAxis& axis,
                             const WaveformProcessing& settings) {
  if (!processable(power_W, axis)) return SignalQuality::none;
  if (settings.noise_free) {
    // Without noise the threshold is a fraction of the smoothed peak: a waveform of no negative
    // value has signal exactly when one value is above 0. Its smoothed peak is then at least
    // that value over the kernel's width (far from underflow above 1e-200), and is 0 when
    // every value is. Anything else (negative values, tiny ones) takes the full threshold.
    bool negative = false;
    double largest = 0.0;
    for (const double p : power_W) {
      negative = negative || p < 0.0;
      largest = std::max(largest, p);
    }
    if (!negative && largest == 0.0) return SignalQuality::none;
    if (!negative && largest >= 1e-200) return SignalQuality::good;
  }
  return threshold_of(power_W, axis, settings).signal;
}

WaveformMetrics process_waveform(std::span<const double> power_W, const WaveformAxis& axis,
                                 const WaveformProcessing& settings,
                                 std::span<const double> mc_variance_W2) {
  WaveformMetrics m = WaveformMetrics::none();
  if (!processable(power_W, axis)) return m;
  const auto bins = power_W.size();
  const double pulse_bins = settings.pulse_sigma_ns / axis.bin_ns;
  const Threshold t = threshold_of(power_W, axis, settings);
  const std::vector<double>& smoothed = t.smoothed;
  const Statistics& noise = t.noise;
  const double above = t.above;
  m.noise_mean_W = noise.mean;
  m.noise_sd_W = noise.sd;
  m.threshold_W = t.threshold_W;
  m.energy_tr_J = m.energy_cr_J = m.energy_gr_J = 0.0;
  m.signal = t.signal;
  if (m.signal == SignalQuality::none) return m;

  const Extent extent = signal_extent(smoothed, m.threshold_W);
  m.sig_begin_bin = extent.begin;
  m.sig_end_bin = extent.end;
  m.sig_begin_m = axis.elevation_m(extent.begin, bins);
  m.sig_end_m = axis.elevation_m(extent.end, bins);

  // Everything below works on the waveform above the noise level.
  std::vector<double> signal(power_W.begin(), power_W.end());
  for (double& v : signal) v -= noise.mean;
  const std::vector<double> variance =
      error_variance(mc_variance_W2, noise.sd / filter_noise_gain(pulse_bins), pulse_bins, bins);
  decompose(signal, variance, extent, pulse_bins, above, settings, axis, m);
  const double split = m.gaussians.empty() ? extent.begin : split_at_ground(axis, bins, m);
  store_partition(partition_energy(signal, extent, split), extent, axis, m);
  return m;
}

ThresholdCrossings threshold_crossings(std::span<const double> smoothed, double front_level,
                                       double back_level) {
  ThresholdCrossings c;
  const int n = static_cast<int>(smoothed.size());
  int first = 0;
  while (first < n && !(smoothed[first] > front_level)) ++first;
  int last = n - 1;
  while (last >= 0 && !(smoothed[last] > back_level)) --last;
  if (first >= n || last < 0 || last < first) return c;
  const double f = front_level, b = back_level;
  c.begin_bin =
      first == 0 ? 0.0
                 : first - 1 + (f - smoothed[first - 1]) / (smoothed[first] - smoothed[first - 1]);
  c.end_bin =
      last == n - 1 ? n - 1.0 : last + (smoothed[last] - b) / (smoothed[last] - smoothed[last + 1]);
  c.found = true;
  return c;
}

BinEnergy energy_between(std::span<const double> signal, double begin_bin, double end_bin) {
  const int n = static_cast<int>(signal.size());
  BinEnergy e;
  e.energy.assign(n, 0.0);
  if (!(end_bin > begin_bin)) return e;
  for (int i = std::max(0, static_cast<int>(std::floor(begin_bin)));
       i <= static_cast<int>(std::ceil(end_bin)) && i < n; ++i) {
    e.energy[i] = signal[i] * overlap(i, begin_bin, end_bin);
    e.total += e.energy[i];
  }
  return e;
}

std::array<double, kRhLevels> cumulative_energy_bins(std::span<const double> energy, double total,
                                                     double begin_bin, double end_bin) {
  const int n = static_cast<int>(energy.size());
  const double begin = begin_bin, end = end_bin;
  std::array<double, kRhLevels> position{};
  int level = 0;
  double cumulative = 0.0;
  for (int i = static_cast<int>(std::ceil(end));
       i >= static_cast<int>(std::floor(begin)) && level < kRhLevels; --i) {
    if (i < 0 || i >= n) continue;
    const double lo = std::max(i - 0.5, begin), hi = std::min(i + 0.5, end);  // lo is higher
    if (hi <= lo) continue;
    while (level < kRhLevels) {
      // Slightly short of the exact share, so that round-off cannot push rh100 past the top.
      const double target = total * (level / 100.0 - 1e-12);
      if (energy[i] > 0.0 && cumulative + energy[i] >= target) {
        const double along = std::clamp((target - cumulative) / energy[i], 0.0, 1.0);
        position[level++] = hi - along * (hi - lo);
      } else {
        break;
      }
    }
    cumulative += energy[i];
  }
  for (; level < kRhLevels; ++level) position[level] = begin;  // round-off at the top
  return position;
}

std::vector<double> process_shot_waveforms(ShotRecord& record, double bin_ns,
                                           const WaveformProcessing& settings,
                                           std::span<const std::vector<double>> mc_variance_W2) {
  const WaveformAxis axis{bin_ns, record.elev_bin0_m, record.elev_lastbin_m};
  const std::size_t bands = record.rx_waveform_W.size();
  fill_fields(record, FieldSource::metrics, ProductShape{.bands = bands});
  std::vector<double> noise_mean_W(bands, nan);
  if (record.quality_flag != quality_good) return noise_mean_W;
  SignalQuality best = SignalQuality::none;
  for (std::size_t band = 0; band < bands; ++band) {
    const std::span<const double> variance = band < mc_variance_W2.size()
                                                 ? std::span<const double>(mc_variance_W2[band])
                                                 : std::span<const double>();
    const WaveformMetrics m =
        process_waveform(record.rx_waveform_W[band], axis, settings, variance);
    store_metrics(record, band, m);
    noise_mean_W[band] = m.noise_mean_W;
    best = std::min(best, m.signal);  // good < low < none
  }
  flag_signal(record, bands, best);
  return noise_mean_W;
}

void flag_shot_signal(ShotRecord& record, double bin_ns, const WaveformProcessing& settings) {
  const WaveformAxis axis{bin_ns, record.elev_bin0_m, record.elev_lastbin_m};
  const std::size_t bands = record.rx_waveform_W.size();
  fill_fields(record, FieldSource::metrics, ProductShape{.bands = bands});
  if (record.quality_flag != quality_good) return;
  SignalQuality best = SignalQuality::none;
  for (std::size_t band = 0; band < bands; ++band)
    best = std::min(best, signal_quality(record.rx_waveform_W[band], axis, settings));
  flag_signal(record, bands, best);
}

}  // namespace glaswave
