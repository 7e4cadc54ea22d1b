// The `rt` retrieval: a measured waveform against every entry of the forward table.
//
// Likelihood. Each band's measured waveform m (its noise mean removed) is Gaussian about the
// entry's waveform T placed with its ground at the elevation g: m_b ~ N(a T(z_b - g), sigma^2),
// over the bins R the table can reach. sigma^2 = noise_sd^2 + (f peak)^2 (1/K + [simulated]):
// the shot's detector noise, plus the Monte Carlo noise of the table's mean of K shots and, for
// simulated input, of the measured shot itself, each one shot's f = the table's measured
// mc_relative_sd times the measured peak (a constant per shot, so that the search below is a
// cross-correlation). The amplitude a is 1 (the table and the shot share the sensor's pulse
// energy and units: the absolute return carries the reflectances and the cover) unless
// free_scale, where a >= 0 is fitted by least squares per entry and ground (for waveforms whose
// calibration is unknown). The ground g is unknown: it is searched over whole bins about a first
// guess (L2A's lowest mode), g(s) = z_0 + s dz - h_0 for the shift s of the table's bins against
// the measured ones, and marginalised.
//
// Posterior. Uniform over the table's entries (the design is the prior) and over the shifts:
// w(e, s) ∝ exp(-chi2(e, s) / 2). Each variable's mean, sd, 5 % and 95 % come from the entries'
// marginal weights (the ground's from the shifts').
//
// Flags (rt_flag, bits): 1 the best chi2 per degree of freedom beyond chi2_dof_limit (the table
// cannot explain the shot), 2 more than edge_mass of the posterior in the outer edge_fraction of
// a varied range (the truth may lie outside the table), 4 the best ground at the search's edge,
// 8 not run (no finite waveform, no signal).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "pipeline/products/waveform_metrics.hpp"
#include "pipeline/retrieval/forward_table.hpp"

namespace glaswave {

enum RtFlag : std::uint8_t {
  rt_misfit = 1,
  rt_table_edge = 2,
  rt_ground_search_edge = 4,
  rt_not_run = 8,
};

struct RtSettings {
  double chi2_dof_limit = 4.0;
  double edge_fraction = 0.05;
  double edge_mass = 0.5;
  // Whole bins searched either side of the first guess of the ground; 0: 1.5 pulse sigma, at
  // least 4.
  int search_half_width_bins = 0;
  bool free_scale = false;
  // The measured shot is a simulation (glaswave's shots.nc): its own Monte Carlo noise counts.
  bool measured_is_simulated = true;
  // One shot's Monte Carlo sd over its peak where the table could not measure it (one shot an
  // entry): 2 %, about what 10^4 rays leave.
  double mc_relative_sd_fallback = 0.02;
  // Overrides the table's measured f (negative: use the table's).
  double mc_relative_sd = -1.0;
};

// One measured shot: its waveforms [band] (W, bins in time order, bin 0 the highest), where they
// lie, each band's noise mean and sd, and a first guess of the ground (NaN: the waveform's
// lowest crossing of 5 % of its peak, raised by 2.45 pulse sigma, where a Gaussian's centre lies).
struct RtShot {
  std::vector<std::span<const double>> waveform;
  WaveformAxis axis;
  std::vector<double> noise_mean_W, noise_sd_W;
  double ground_guess_m = 0.0;
};

struct RtStatistic {
  double mean = 0.0, sd = 0.0, p05 = 0.0, p95 = 0.0;
};

struct RtResult {
  RtStatistic canopy_height_m, cover, pai, ground_elevation_m, rhov_rhog;
  double chi2_min = 0.0;
  double dof = 0.0;
  std::uint8_t flag = 0;
  std::int64_t best_entry = -1;
  static RtResult none();  // NaN statistics, flag rt_not_run
};

// A shot made ready for the search: its waveforms less their noise means, its sigma per band,
// the shifts searched and the bins R compared.
struct RtPreparedShot {
  std::vector<std::vector<double>> measured;  // [band][bin]
  std::vector<double> sigma;                  // [band]
  std::vector<double> m2;                     // [band] sum of m^2 over R
  double z0_m = 0.0, dz_m = 0.0;              // bin 0's elevation, and the step per bin
  int first_shift = 0, last_shift = 0;        // inclusive
  std::size_t region_begin = 0, region_end = 0;  // R = [begin, end) of the measured bins
  bool usable = false;
};

class RtInversion {
 public:
  // Refuses (an input error naming `table_place`) a table whose bands or bins differ from the
  // measured shots' (`band_names`, `bin_ns`).
  RtInversion(const ForwardTable& table, const RtSettings& settings);

  // Checks that shots of these bands and bin width can be compared with the table.
  void check_compatible(const std::vector<std::string>& band_names, double bin_ns,
                        const std::string& table_place) const;

  RtPreparedShot prepare(const RtShot& shot) const;
  // The ground elevation of a shift.
  double ground_elevation_m(const RtPreparedShot& shot, int shift) const;
  // chi2 of one entry at one shift over R (and the amplitude used).
  struct Fit {
    double chi2 = 0.0, scale = 1.0;
  };
  Fit fit(const RtPreparedShot& shot, std::size_t entry, int shift) const;

  RtResult invert(const RtShot& shot) const;

 private:
  const ForwardTable& table_;
  RtSettings settings_;
  double mc_relative_sd_;
  // Per entry and band: the bins [support_begin, support_end) above 1e-4 of the peak, and the
  // prefix sums of T^2.
  std::vector<std::vector<std::size_t>> support_begin_, support_end_;
  std::vector<std::vector<std::vector<double>>> prefix_tt_;
  // Entry indices sorted by each variable (height, cover, pai, rhov_rhog), for the quantiles.
  std::vector<std::vector<std::uint32_t>> sorted_;
  // Per entry: whether it lies in the outer edge of a varied range, low or high, per parameter.
  std::vector<std::vector<std::uint8_t>> edge_;
};

}  // namespace glaswave
