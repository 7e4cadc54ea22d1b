// What ATL08 makes of a beam's photon cloud, from the photons alone (never from the simulation's
// truth): noise removed by a neighbour count (after DRAGANN), the ground as a surface fitted to the
// lowest signal photons and refined iteratively, canopy above it and the top of the canopy
// above that, then the 100 m land segments' terrain height, canopy height (98th percentile of the
// canopy's heights above the ground) and openness, as the ATL08 ATBD (Neuenschwander et al.)
// describes them, simplified and stated below.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace glaswave {

struct Atl08Settings {
  double search_along_m = 10.0;    // the neighbour count's half length along track
  double search_vertical_m = 3.0;  // and half height
  double noise_sigmas = 2.5;       // signal: neighbours above the noise's mean + this many sigmas
  double cell_m = 10.0;            // along-track cells of the ground fit
  double min_ground_band_m = 0.5;  // ground photons lie within this of the fit at least
  double top_of_canopy_quantile =
      0.9;                            // canopy photons at or above it in their cell: top of canopy
  double segment_m = 100.0;           // land segments
  int min_ground_photons = 5;         // for a segment's terrain height
  int min_canopy_photons = 5;         // for its canopy height and openness, and
  double min_canopy_fraction = 0.05;  // this part of its signal photons (ATL08's rule)
};

// One photon as the classification sees it: along-track distance and height, and the density of
// background photons expected about it (per m along track per m of height), which ATL03 gives
// from the background rate the instrument measures (bckgrd_atlas/bckgrd_rate):
// rate * 2 / c per shot, over the shots' spacing.
struct CloudPhoton {
  double along_m = 0.0;
  double h_m = 0.0;
  double noise_per_m2 = 0.0;
};

struct Atl08Classes {
  // Per photon, in the input's order: 0 noise, 1 ground, 2 canopy, 3 top of canopy (ATL08's
  // classed_pc_flag), and an ATL03-like signal confidence 0 (noise), 2, 3 or 4 (low, medium,
  // high: neighbours at least 1, 1.5 and 2 times the signal threshold).
  std::vector<std::uint8_t> classes;
  std::vector<std::int8_t> confidence;
  // The ground surface: heights at the cells' centres, the first centred on first_cell_m.
  double first_cell_m = 0.0;
  double cell_m = 0.0;
  std::vector<double> ground_m;

  // The fitted ground at an along-track distance (linear between cell centres, constant beyond).
  double ground_at(double along_m) const;
};

// Classifies a beam's photons (any order). The steps:
// 1. Signal: a photon's neighbours within +-search_along_m and +-search_vertical_m are counted;
//    the noise's mean count mu is its noise density times the box's area, and a photon is signal
//    when its count exceeds mu + noise_sigmas sqrt(mu) + 1.
// 2. Ground: in each cell the lowest 1 m bin of signal photons holding at least 3 of them and a
//    tenth of the fullest bin's is a candidate; candidates more than 5 m above
//    the median of their five-cell neighbourhood (canopy-only cells) are dropped and the gaps
//    interpolated; then three times, with bands of 3, 1.5 and 1 m, each cell's ground becomes the
//    median of the signal photons within the band about the surface.
// 3. Classes: signal photons within max(min_ground_band_m, 2.5 sigma) of the surface are ground
//    (sigma: 1.4826 times the median absolute residual of those within 1.5 m), higher ones canopy,
//    the canopy photons at or above their cell's top_of_canopy_quantile of canopy heights top of
//    canopy; lower ones and the rest are noise.
Atl08Classes classify_photons(std::span<const CloudPhoton> photons, const Atl08Settings& settings);

// A 100 m land segment's estimates (fill: NaN where there are too few photons).
struct LandSegment {
  double start_m = 0.0;  // along track
  double h_te_best_fit = 0.0;
  double h_te_mean = 0.0, h_te_median = 0.0;  // of the ground photons' heights
  double h_te_min = 0.0, h_te_max = 0.0;
  double h_te_uncertainty = 0.0;  // their scatter about the fitted line over sqrt(n_te_photons)
  double h_te_std = 0.0;          // their heights' standard deviation (n - 1)
  double terrain_slope = 0.0;     // the least-squares line's slope through them (dh / d along)
  double h_canopy = 0.0;         // 98th percentile of canopy and top-of-canopy heights above ground
  double canopy_openness = 0.0;  // their standard deviation
  double h_mean_canopy = 0.0;    // their mean
  double toc_roughness = 0.0;    // the top-of-canopy photons' heights' standard deviation
  double h_min_canopy = 0.0, h_median_canopy = 0.0, h_max_canopy = 0.0;
  std::array<double, 18> canopy_h_metrics{};  // their 10th, 15th, ..., 95th percentiles
  // Its five sub-segments (ATL08's 20 m with 100 m segments): the fitted ground at each centre
  // with at least 3 ground photons, the 98th percentile of the canopy heights with at least
  // min_canopy_photons.
  std::array<double, 5> h_te_best_fit_20m{}, h_canopy_20m{};
  double h_mean_canopy_abs = 0.0;  // the mean of their heights above the ellipsoid
  std::int32_t n_te_photons = 0, n_ca_photons = 0, n_toc_photons = 0;
  std::int32_t n_noise_photons = 0;  // the segment's photons classified noise
  // The mode of the ground photons' heights in 0.1 m bins centred on multiples of 0.1 m (real
  // ATL08's h_te_mode lies on that grid), the lowest of tied bins; NaN without ground photons.
  double h_te_mode = 0.0;
  // ATL08's canopy_rh_conf from the shares of canopy (canopy and top of canopy) and ground
  // photons among the classified ones: 0 canopy < 5 %, 1 canopy >= 5 % and ground < 5 %, 2 both
  // >= 5 %; -1 (fill) without classified photons.
  std::int8_t canopy_rh_conf = -1;
};

// The land segments covering [first_m, end_m) every segment_m, from the classified photons:
// h_te_best_fit is the ground surface at the segment's centre, and the ground photons' mean,
// median, slope and uncertainty, with at least min_ground_photons; the canopy's metrics need
// min_canopy_photons canopy and top-of-canopy photons and min_canopy_fraction of the segment's
// signal photons (ground, canopy and top of canopy).
std::vector<LandSegment> land_segments(std::span<const CloudPhoton> photons,
                                       const Atl08Classes& classes, double first_m, double end_m,
                                       const Atl08Settings& settings);

}  // namespace glaswave
