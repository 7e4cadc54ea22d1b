// GEDI L2A's setting groups and their selection: the rules are set out in the header.
#include "pipeline/products/gedi_l2a_groups.hpp"

#include <cmath>
#include <limits>
#include <vector>

#include "pipeline/products/gaussian_decomposition.hpp"

namespace glaswave {
namespace {

constexpr double nan = std::numeric_limits<double>::quiet_NaN();

L2aGroupResult no_signal() {
  L2aGroupResult r;
  r.toploc_bin = r.botloc_bin = nan;
  r.elev_highestreturn_m = r.elev_lowestreturn_m = nan;
  r.lowestmode_bin = r.elev_lowestmode_m = nan;
  r.rh_m.fill(nan);
  return r;
}

bool usable(const L2aWaveform& input) {
  if (input.waveform.size() < 3 || !(input.axis.bin_ns > 0.0)) return false;
  if (!std::isfinite(input.noise_mean) || !(input.noise_sd > 0.0)) return false;
  for (const double v : input.waveform)
    if (!std::isfinite(v)) return false;
  return true;
}

// The maxima of `smoothed` strictly inside [begin, end] standing above `level`: where the
// forward difference d[i] = s[i+1] - s[i] (located at i + 1/2) turns from positive to not
// positive, interpolated linearly between i - 1/2 and i + 1/2 (exact for a peak symmetric about
// a bin or a half bin).
std::vector<double> modes(const std::vector<double>& smoothed, double begin, double end,
                          double level) {
  std::vector<double> found;
  const int n = static_cast<int>(smoothed.size());
  for (int i = 1; i + 1 < n; ++i) {
    const double rise = smoothed[i] - smoothed[i - 1], fall = smoothed[i + 1] - smoothed[i];
    if (!(rise > 0.0 && fall <= 0.0)) continue;
    const double at = i - 0.5 + rise / (rise - fall);
    if (at < begin || at > end || !(smoothed[i] > level)) continue;
    found.push_back(at);
  }
  return found;
}

}  // namespace

L2aGroupResult process_l2a_group(const L2aWaveform& input, const L2aGroupSettings& group) {
  L2aGroupResult r = no_signal();
  if (!usable(input)) return r;
  const std::size_t bins = input.waveform.size();
  const double front = input.noise_mean + group.front_sigmas * input.noise_sd;
  const double back = input.noise_mean + group.back_sigmas * input.noise_sd;
  const std::vector<double> located = gaussian_smooth(input.waveform, group.smooth_width_bins);
  const ThresholdCrossings extent = threshold_crossings(located, front, back);
  if (!extent.found) return r;
  r.signal = true;
  r.toploc_bin = extent.begin_bin;
  r.botloc_bin = extent.end_bin;
  r.elev_highestreturn_m = input.axis.elevation_m(r.toploc_bin, bins);
  r.elev_lowestreturn_m = input.axis.elevation_m(r.botloc_bin, bins);

  const std::vector<double> peaked = gaussian_smooth(input.waveform, group.zcross_width_bins);
  const std::vector<double> found = modes(peaked, r.toploc_bin, r.botloc_bin, back);
  r.num_detectedmodes = static_cast<int>(found.size());
  if (found.empty()) return r;
  r.has_ground = true;
  r.lowestmode_bin = found.back();
  r.elev_lowestmode_m = input.axis.elevation_m(r.lowestmode_bin, bins);

  std::vector<double> signal(input.waveform.begin(), input.waveform.end());
  for (double& v : signal) v -= input.noise_mean;
  const BinEnergy energy = energy_between(signal, r.toploc_bin, r.botloc_bin);
  if (!(energy.total > 0.0)) return r;
  const std::array<double, kRhLevels> position =
      cumulative_energy_bins(energy.energy, energy.total, r.toploc_bin, r.botloc_bin);
  for (int k = 0; k < kRhLevels; ++k)
    r.rh_m[k] = input.axis.elevation_m(position[k], bins) - r.elev_lowestmode_m;
  return r;
}

int select_l2a_group(std::span<const L2aGroupResult> groups, const L2aSelection& selection) {
  int lowest = -1;
  for (int k = 0; k < static_cast<int>(groups.size()); ++k)
    if (groups[k].has_ground &&
        (lowest < 0 || groups[k].elev_lowestmode_m < groups[lowest].elev_lowestmode_m))
      lowest = k;
  if (lowest < 0) return -1;
  for (int k = 0; k < static_cast<int>(groups.size()); ++k)
    if (groups[k].has_ground &&
        groups[k].elev_lowestmode_m - groups[lowest].elev_lowestmode_m <= selection.same_mode_m)
      return k;
  return lowest;
}

const L2aGroupResult& L2aResult::selected() const {
  return selected_algorithm > 0 ? groups[selected_algorithm - 1] : groups[0];
}

L2aResult process_l2a(const L2aWaveform& input,
                      const std::array<L2aGroupSettings, kL2aGroups>& groups,
                      const L2aSelection& selection) {
  L2aResult result;
  for (int k = 0; k < kL2aGroups; ++k) result.groups[k] = process_l2a_group(input, groups[k]);
  result.selected_algorithm = select_l2a_group(result.groups, selection) + 1;
  return result;
}

}  // namespace glaswave
