// GLAS/GEDI-style metrics of one received waveform (PRODUCT.md section 4): noise level, signal
// begin and end, centroid, Gaussian decomposition, ground and canopy height, relative heights
// rh0..rh100, and the seed's TR/CR/GR partition by position in the waveform with its waveform
// index (eq. 3). Heights are elevations along the waveform's own axis (elev_bin0 to
// elev_lastbin), so the metrics need nothing from the simulation but the waveform.
//
// The rules, in waveform order (bin 0 is the earliest, the highest):
// - Noise: none for a noise-free waveform; otherwise the mean and standard deviation of the
//   quieter end of the window (the first or the last noise_fraction of the bins).
// - Threshold: the waveform is smoothed with a Gaussian of the pulse's width (as GLAS does) and
//   the signal is where the smoothed waveform exceeds mean + max(noise_sigmas * sd,
//   peak_fraction * (peak - mean)): GLA14's noise threshold, with a fraction of the peak as the
//   floor that a noise-free waveform needs. Signal begin and end are the first and last
//   crossings, interpolated between bins.
// - Gaussians: up to 6 fitted to the waveform (noise mean removed) over the signal's extent and
//   3 pulse widths beyond (gaussian_decomposition.hpp). Where the waveform's noise is known (the
//   detector's, and the Monte Carlo variance of the rays' scores), a component is kept only
//   when it lowers chi^2 significantly: the noise of a simulation of few rays on a broad return
//   is not split into returns. The ground is the centre of the lowest one whose amplitude is at
//   least 2 % of the strongest's and that is a peak of its own (below it, a fit finds only the
//   faint, broad tail of light scattered many times in the crowns, which arrives late); the
//   lowest strong one where none is.
// - Energy above the noise between signal begin and end is split at a height above the ground:
//   4 sigma of the ground Gaussian above its centre, or lower where the other Gaussians already
//   outweigh the ground's. Below is GR, above is CR, TR = CR + GR.
// - rh k: the height above the ground at which the energy counted up from signal end reaches
//   k % of TR (GEDI L2A), each bin's energy spread evenly over the bin: rh0 and rh100 are the
//   bottom and the top of the energy (signal end and begin, when the waveform reaches them).
// - canopy_height: signal begin above the ground, as the product contract and GLA14 define it
//   (= rh100); over bare ground it is the pulse's own rise to the threshold, about 3 m.
// - No signal above the threshold: TR = CR = GR = 0, n_peaks 0, everything else NaN.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "pipeline/products/gaussian_decomposition.hpp"
#include "pipeline/products/shot_record.hpp"

namespace glaswave {

constexpr int kMaxGaussians = 6;  // PRODUCT.md: up to 6 Gaussians
constexpr int kRhLevels = 101;    // rh0 .. rh100

// Where the bins of a waveform are.
struct WaveformAxis {
  double bin_ns = 1.0;
  double elev_bin0_m = 0.0;     // elevation of the centre of bin 0
  double elev_lastbin_m = 0.0;  // elevation of the centre of the last bin

  // Elevation at a fractional bin index (linear between the first and the last bin).
  double elevation_m(double bin, std::size_t bins) const;
};

struct WaveformProcessing {
  double pulse_sigma_ns = 5.0;
  // True when the waveform carries no noise (no detector model): the threshold is then a
  // fraction of the peak alone and the noise level is exactly 0.
  bool noise_free = true;
  double noise_sigmas = 4.0;
  double peak_fraction = 0.01;
  double noise_fraction = 0.15;  // of the bins at each end of the window, for the noise level
  double min_gaussian_area_fraction = 0.005;
  // A waveform whose smoothed peak stands less than this many noise sd above the noise mean
  // (the detector's noise, measured) is "low signal"; nothing above the threshold: "no signal".
  double low_signal_sigmas = 8.0;
};

// What the waveform holds, for the shot's quality_flag and quality_reason.
enum class SignalQuality { good, low, none };

struct WaveformMetrics {
  double noise_mean_W = 0.0;
  double noise_sd_W = 0.0;   // of the smoothed waveform (the raw noise RMS through the filter)
  double threshold_W = 0.0;  // on the smoothed waveform, noise mean included
  SignalQuality signal = SignalQuality::none;
  double energy_tr_J = 0.0, energy_cr_J = 0.0, energy_gr_J = 0.0;
  double waveform_index = 0.0;                                  // (CR - GR) / (CR + GR)
  double sig_begin_m = 0.0, sig_end_m = 0.0, centroid_m = 0.0;  // elevations
  double sig_begin_bin = 0.0, sig_end_bin = 0.0;                // fractional bins
  int n_peaks = 0;
  std::vector<GaussianComponent> gaussians;  // in bin units, waveform order
  // Per Gaussian slot (kMaxGaussians), NaN where unused.
  std::array<double, kMaxGaussians> gauss_amp_W{}, gauss_center_m{}, gauss_sigma_ns{},
      gauss_area_J{};
  double ground_elev_m = 0.0;
  double canopy_height_m = 0.0;
  std::array<double, kRhLevels> rh_m{};

  // Every value NaN (n_peaks 0): a waveform with no signal above the threshold, or fill.
  static WaveformMetrics none();
};

// The metrics of `power_W` (bins in time order). A waveform with a non-finite value, or with
// nothing above the threshold, gives none() with its noise statistics (and TR = CR = GR = 0
// when it is finite but empty).
// `mc_variance_W2`, when given (one value a bin), is the Monte Carlo variance of power_W: with
// the detector's noise it weighs the decomposition's test of each component (a component must
// explain more than noise), so that the noise of a simulation of few rays is not taken for
// returns.
WaveformMetrics process_waveform(std::span<const double> power_W, const WaveformAxis& axis,
                                 const WaveformProcessing& settings,
                                 std::span<const double> mc_variance_W2 = {});

// What process_waveform(power_W, axis, settings).signal is, without the decomposition and the
// metrics: the smoothed waveform against its threshold alone, or less where the waveform has no
// noise (signal exactly when a value is above 0, for a waveform of no negative value).
SignalQuality signal_quality(std::span<const double> power_W, const WaveformAxis& axis,
                             const WaveformProcessing& settings);

// Where a smoothed waveform crosses its thresholds, as fractional bins: `begin` where it first
// rises above `front_level`, `end` where it last stands above `back_level`, each interpolated
// linearly between the bins either side (GLA14's and GEDI L2A's toploc and botloc). `found` is
// false when no value exceeds either level or the end would come before the begin.
struct ThresholdCrossings {
  bool found = false;
  double begin_bin = 0.0, end_bin = 0.0;
};
ThresholdCrossings threshold_crossings(std::span<const double> smoothed, double front_level,
                                       double back_level);

// The energy of `signal` (noise level removed) between two fractional bins, each bin's value
// spread evenly over the bin ([i - 0.5, i + 0.5]) and counted for its part inside: per bin, and
// the total.
struct BinEnergy {
  std::vector<double> energy;
  double total = 0.0;
};
BinEnergy energy_between(std::span<const double> signal, double begin_bin, double end_bin);

// Where the energy counted up from `end_bin` reaches k % of `total` (k = 0..100), as fractional
// bins: GEDI L2A's relative heights before the ground is subtracted. Level 0 is end_bin, level 100
// begin_bin. `energy` is energy_between's per bin; `total` > 0.
std::array<double, kRhLevels> cumulative_energy_bins(std::span<const double> energy, double total,
                                                     double begin_bin, double end_bin);

// Processes every band of record.rx_waveform_W (bins of `bin_ns`, between elev_bin0_m and
// elev_lastbin_m) and stores the metrics in the record's per-band fields. A band whose waveform
// is fill (a flagged shot) gets fill, with n_peaks 0. A shot none of whose bands has signal is
// flagged (quality_flag 0) "no signal"; one none of whose bands has more than a low signal, "low
// signal"; the metrics stay. Returns each band's noise mean (W), 0 for a noise-free waveform.
// `mc_variance_W2` [band][bin], when given, is each band's Monte Carlo variance (W^2).
std::vector<double> process_shot_waveforms(
    ShotRecord& record, double bin_ns, const WaveformProcessing& settings,
    std::span<const std::vector<double>> mc_variance_W2 = {});

// The shot's flags as process_shot_waveforms sets them (no signal, low signal), its metrics left
// fill: for a run whose products read no metric (a photon-counting run's ICESat-2 granules), which
// still counts its flagged shots.
void flag_shot_signal(ShotRecord& record, double bin_ns, const WaveformProcessing& settings);

}  // namespace glaswave
