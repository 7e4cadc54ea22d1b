// GEDI L2A's six algorithm setting groups (a1..a6) on one received waveform, and the choice of
// one of them per shot (Hofton & Blair, GEDI L1/L2 waveform processing ATBD; the L2A data
// dictionary's ancillary settings). Each group smooths the waveform twice with a Gaussian: with
// the location width (6.5 bins in every group) to find where the signal begins and ends (toploc:
// the first rise above front_sigmas noise standard deviations over the noise mean; botloc: the
// last point above back_sigmas), and with its zero-crossing width to find the modes (maxima: the
// first derivative's zero crossings from + to -, inside [toploc, botloc] and above the back
// threshold). The lowest mode is the ground (elev_lowestmode); rh k is the height above it where
// the energy (noise mean removed) counted up from botloc reaches k % of the energy between botloc
// and toploc, as waveform_metrics counts it (rh0 = botloc, rh100 = toploc).
//
// The selected group (L2A's selected_algorithm) is, as the L2A dictionary defines it, the one
// that identifies the lowest non-noise mode: of the groups that find a mode, the one whose lowest
// mode is lowest; groups whose lowest modes lie within same_mode_m of that one found the same
// return, and the first of them in the mission's order (a1 first, the default group) is chosen.
// The released product's further tests of a candidate ground (its amplitude and energy limits,
// the ancillary amp_thresh, botlocdist_limit, ampval_limit, cumulative_energy_thresh) are not
// reproduced: a mode is non-noise here when it stands above its group's back threshold.
#pragma once

#include <array>
#include <span>

#include "pipeline/products/waveform_metrics.hpp"

namespace glaswave {

constexpr int kL2aGroups = 6;

// One setting group. Widths are the sigma of the Gaussian smoothing filter in bins (GEDI's
// 1 ns samples); thresholds are multiples of the noise standard deviation above the noise mean.
struct L2aGroupSettings {
  double smooth_width_bins = 6.5;  // the location step's (toploc, botloc)
  double zcross_width_bins = 6.5;  // the modes'
  double front_sigmas = 3.0;       // toploc
  double back_sigmas = 6.0;        // botloc
};

// The mission's a1..a6 (GEDI L2A ATBD's table of setting groups; issue 37).
inline constexpr std::array<L2aGroupSettings, kL2aGroups> kGediL2aGroups = {{
    {6.5, 6.5, 3.0, 6.0},  // a1, the default
    {6.5, 3.5, 3.0, 3.0},  // a2
    {6.5, 3.5, 3.0, 6.0},  // a3
    {6.5, 6.5, 6.0, 6.0},  // a4
    {6.5, 3.5, 3.0, 2.0},  // a5
    {6.5, 3.5, 3.0, 4.0},  // a6
}};

// One shot's received waveform as L1B holds it: rxwaveform (bins in time order, bin 0 the
// highest), elevation_bin0 and elevation_lastbin, and the noise (noise_mean_corrected,
// noise_stddev_corrected), all in the waveform's own unit (L1B's counts, glaswave's W).
struct L2aWaveform {
  std::span<const double> waveform;
  WaveformAxis axis;
  double noise_mean = 0.0;
  double noise_sd = 0.0;
};

// What one group finds. Elevations in metres, positions in fractional bins; NaN where not found.
struct L2aGroupResult {
  bool signal = false;      // a toploc and a botloc were found
  bool has_ground = false;  // and a mode between them: the rest is valid
  double toploc_bin = 0.0, botloc_bin = 0.0;
  double elev_highestreturn_m = 0.0;  // at toploc
  double elev_lowestreturn_m = 0.0;   // at botloc
  int num_detectedmodes = 0;
  double lowestmode_bin = 0.0;
  double elev_lowestmode_m = 0.0;  // the ground
  std::array<double, kRhLevels> rh_m{};
};

// One group on one waveform. Throws nothing: a waveform with a non-finite value, fewer than 3
// bins, no noise standard deviation above 0 or no signal gives signal = false and NaN.
L2aGroupResult process_l2a_group(const L2aWaveform& input, const L2aGroupSettings& group);

struct L2aSelection {
  // Lowest modes within this of the lowest are the same return (about 3 GEDI bins).
  double same_mode_m = 0.5;
};

// Every group and the selected one.
struct L2aResult {
  std::array<L2aGroupResult, kL2aGroups> groups{};
  int selected_algorithm = 0;  // 1..6 as L2A numbers them; 0 when no group finds a ground

  // The selected group's result; `groups[0]` (a1) when none is selected.
  const L2aGroupResult& selected() const;
};

// The index (0-based) of the group that identifies the lowest non-noise mode, as set out above;
// -1 when none has a ground.
int select_l2a_group(std::span<const L2aGroupResult> groups, const L2aSelection& selection = {});

// The six groups (kGediL2aGroups unless given) and the selection, for one shot.
L2aResult process_l2a(const L2aWaveform& input,
                      const std::array<L2aGroupSettings, kL2aGroups>& groups = kGediL2aGroups,
                      const L2aSelection& selection = {});

}  // namespace glaswave
