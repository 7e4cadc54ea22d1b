// Waveform metrics: threshold, extent, decomposition, partition and relative heights of one
// waveform. The rules are set out in the header.
#include "pipeline/products/waveform_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace glaswave {
namespace {

constexpr double nan = std::numeric_limits<double>::quiet_NaN();
// Split between canopy and ground: this many sigma of the ground Gaussian above its centre
// holds all but 3e-5 of the ground's energy.
constexpr double kSplitSigmas = 4.0;
// A ground Gaussian's amplitude is at least this part of the strongest Gaussian's.
constexpr double kGroundMinAmplitude = 0.05;

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

// The part of bin i ([i - 0.5, i + 0.5]) that lies in [a, b].
double overlap(int i, double a, double b) {
  return std::max(0.0, std::min(i + 0.5, b) - std::max(i - 0.5, a));
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
  m.ground_elev_m = m.canopy_height_m = m.split_elev_m = nan;
  m.rh_m.fill(nan);
  return m;
}

WaveformMetrics process_waveform(std::span<const double> power_W, const WaveformAxis& axis,
                                 const WaveformProcessing& settings) {
  WaveformMetrics m = WaveformMetrics::none();
  const int n = static_cast<int>(power_W.size());
  if (n < 3 || !(axis.bin_ns > 0.0)) return m;
  for (double p : power_W)
    if (!std::isfinite(p)) return m;
  const auto bins = static_cast<std::size_t>(n);
  const double pulse_bins = settings.pulse_sigma_ns / axis.bin_ns;
  const std::vector<double> smoothed = gaussian_smooth(power_W, pulse_bins);

  // Noise level from the quieter end of the window: the return sits inside it, but tall canopy
  // on steep ground may reach one end.
  double noise_mean = 0.0, noise_sd = 0.0;
  if (!settings.noise_free) {
    const int end_bins = std::clamp(static_cast<int>(settings.noise_fraction * n), 2, n);
    const Statistics head = statistics(power_W.subspan(0, end_bins));
    const Statistics tail = statistics(power_W.subspan(n - end_bins));
    const bool use_head = head.mean <= tail.mean;
    noise_mean = use_head ? head.mean : tail.mean;
    noise_sd = (use_head ? head.sd : tail.sd) * filter_noise_gain(pulse_bins);
  }
  m.noise_mean_W = noise_mean;
  m.noise_sd_W = noise_sd;
  const double peak = *std::max_element(smoothed.begin(), smoothed.end());
  const double above =
      std::max(settings.noise_sigmas * noise_sd, settings.peak_fraction * (peak - noise_mean));
  m.threshold_W = noise_mean + above;
  m.energy_tr_J = m.energy_cr_J = m.energy_gr_J = 0.0;
  if (!(peak > m.threshold_W) || !(above > 0.0)) return m;  // no signal

  // Signal begin and end: the first and last crossings of the threshold, between bins.
  int first = 0;
  while (smoothed[first] <= m.threshold_W) ++first;
  int last = n - 1;
  while (smoothed[last] <= m.threshold_W) --last;
  const double t = m.threshold_W;
  const double begin =
      first == 0 ? 0.0
                 : first - 1 + (t - smoothed[first - 1]) / (smoothed[first] - smoothed[first - 1]);
  const double end =
      last == n - 1 ? n - 1.0 : last + (smoothed[last] - t) / (smoothed[last] - smoothed[last + 1]);
  m.sig_begin_bin = begin;
  m.sig_end_bin = end;
  m.sig_begin_m = axis.elevation_m(begin, bins);
  m.sig_end_m = axis.elevation_m(end, bins);

  // Everything below works on the waveform above the noise level.
  std::vector<double> signal(power_W.begin(), power_W.end());
  for (double& v : signal) v -= noise_mean;

  DecompositionSettings decomposition;
  decomposition.max_components = kMaxGaussians;
  decomposition.min_sigma_bins = pulse_bins;
  decomposition.smooth_sigma_bins = pulse_bins;
  decomposition.significance_level = above;
  decomposition.min_area_fraction = settings.min_gaussian_area_fraction;
  // The fit sees the pulse's tails beyond the threshold crossings too.
  const int margin = static_cast<int>(std::ceil(3.0 * pulse_bins));
  m.gaussians = decompose_waveform(signal, static_cast<int>(std::floor(begin)) - margin,
                                   static_cast<int>(std::ceil(end)) + margin, decomposition);
  m.n_peaks = static_cast<int>(m.gaussians.size());
  for (int k = 0; k < m.n_peaks && k < kMaxGaussians; ++k) {
    const GaussianComponent& g = m.gaussians[k];
    m.gauss_amp_W[k] = g.amplitude;
    m.gauss_center_m[k] = axis.elevation_m(g.center_bin, bins);
    m.gauss_sigma_ns[k] = g.sigma_bins * axis.bin_ns;
    m.gauss_area_J[k] = g.area() * axis.bin_ns * 1e-9;
  }

  // The split between canopy and ground, as a fractional bin (larger is lower). Without a
  // Gaussian there is no ground to split at: CR and GR are then left NaN below.
  double split = begin;
  if (!m.gaussians.empty()) {
    // The ground: the lowest Gaussian that is a peak of its own, as strong as a surface return
    // is. Light scattered many times in the crowns arrives late and trails below the ground as a
    // faint, broad tail, which a fit covers with a broad Gaussian of a few % of the peak; a
    // ground return, pulse-wide, stands far higher even under dense crowns.
    double strongest = 0.0;
    for (const GaussianComponent& g : m.gaussians) strongest = std::max(strongest, g.amplitude);
    std::size_t ground_index = m.gaussians.size() - 1;
    while (ground_index > 0 &&
           m.gaussians[ground_index].amplitude < kGroundMinAmplitude * strongest)
      --ground_index;
    const GaussianComponent& ground = m.gaussians[ground_index];
    m.ground_elev_m = axis.elevation_m(ground.center_bin, bins);
    split = ground.center_bin - kSplitSigmas * ground.sigma_bins;
    // Where the canopy's Gaussians outweigh the ground's before that, the split comes down.
    for (double x = ground.center_bin; x > split; x -= 0.05) {
      double others = 0.0;
      for (std::size_t k = 0; k < ground_index; ++k) others += m.gaussians[k].value_at(x);
      if (others > ground.value_at(x)) {
        split = x;
        break;
      }
    }
    m.split_elev_m = axis.elevation_m(split, bins);
  }

  // Energies between signal begin and end, by part of each bin.
  const double joules_per_bin = axis.bin_ns * 1e-9;
  double canopy = 0.0, ground = 0.0, moment = 0.0;
  std::vector<double> energy(n, 0.0);  // per bin, within [begin, end]
  for (int i = static_cast<int>(std::floor(begin)); i <= static_cast<int>(std::ceil(end)) && i < n;
       ++i) {
    if (i < 0) continue;
    energy[i] = signal[i] * overlap(i, begin, end);
    moment += energy[i] * i;
    canopy += signal[i] * overlap(i, begin, std::min(split, end));
    ground += signal[i] * overlap(i, std::max(split, begin), end);
  }
  const double total = canopy + ground;
  if (total > 0.0) m.centroid_m = axis.elevation_m(moment / total, bins);
  if (m.gaussians.empty()) {
    m.energy_tr_J = total * joules_per_bin;
    m.energy_cr_J = m.energy_gr_J = nan;
    return m;
  }
  m.energy_cr_J = canopy * joules_per_bin;
  m.energy_gr_J = ground * joules_per_bin;
  m.energy_tr_J = m.energy_cr_J + m.energy_gr_J;
  if (m.energy_tr_J > 0.0) m.waveform_index = (m.energy_cr_J - m.energy_gr_J) / m.energy_tr_J;

  // rh: counted up from signal end, each bin's energy spread evenly over its part in [begin, end].
  if (total > 0.0) {
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
    for (int k = 0; k < kRhLevels; ++k)
      m.rh_m[k] = axis.elevation_m(position[k], bins) - m.ground_elev_m;
  }

  // Canopy height as the product contract and GLA14 define it: signal begin above the ground.
  // It includes the pulse's own rise to the threshold (about 3 m for a 5 ns pulse over bare
  // ground with no noise), as the instrument's products do.
  m.canopy_height_m = m.sig_begin_m - m.ground_elev_m;
  return m;
}

std::vector<double> process_shot_waveforms(ShotRecord& record, double bin_ns,
                                           const WaveformProcessing& settings) {
  const WaveformAxis axis{bin_ns, record.elev_bin0_m, record.elev_lastbin_m};
  const std::size_t bands = record.rx_waveform_W.size();
  for (auto field :
       {&ShotRecord::energy_tr_J, &ShotRecord::energy_cr_J, &ShotRecord::energy_gr_J,
        &ShotRecord::waveform_index, &ShotRecord::sig_begin_m, &ShotRecord::sig_end_m,
        &ShotRecord::centroid_m, &ShotRecord::ground_elev_est_m, &ShotRecord::canopy_height_est_m})
    (record.*field).assign(bands, nan);
  record.n_peaks.assign(bands, 0);
  for (auto field : {&ShotRecord::gauss_amp_W, &ShotRecord::gauss_center_m,
                     &ShotRecord::gauss_sigma_ns, &ShotRecord::gauss_area_J})
    (record.*field).assign(bands, std::vector<double>(kMaxGaussians, nan));
  record.rh_m.assign(bands, std::vector<double>(kRhLevels, nan));
  std::vector<double> noise_mean_W(bands, nan);
  if (record.quality_flag != quality_good) return noise_mean_W;
  for (std::size_t band = 0; band < bands; ++band) {
    const WaveformMetrics m = process_waveform(record.rx_waveform_W[band], axis, settings);
    record.energy_tr_J[band] = m.energy_tr_J;
    record.energy_cr_J[band] = m.energy_cr_J;
    record.energy_gr_J[band] = m.energy_gr_J;
    record.waveform_index[band] = m.waveform_index;
    record.sig_begin_m[band] = m.sig_begin_m;
    record.sig_end_m[band] = m.sig_end_m;
    record.centroid_m[band] = m.centroid_m;
    record.ground_elev_est_m[band] = m.ground_elev_m;
    record.canopy_height_est_m[band] = m.canopy_height_m;
    record.n_peaks[band] = m.n_peaks;
    record.gauss_amp_W[band].assign(m.gauss_amp_W.begin(), m.gauss_amp_W.end());
    record.gauss_center_m[band].assign(m.gauss_center_m.begin(), m.gauss_center_m.end());
    record.gauss_sigma_ns[band].assign(m.gauss_sigma_ns.begin(), m.gauss_sigma_ns.end());
    record.gauss_area_J[band].assign(m.gauss_area_J.begin(), m.gauss_area_J.end());
    record.rh_m[band].assign(m.rh_m.begin(), m.rh_m.end());
    noise_mean_W[band] = m.noise_mean_W;
  }
  return noise_mean_W;
}

}  // namespace glaswave
