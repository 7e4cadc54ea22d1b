// The `rt` retrieval: a measured waveform against every entry of the forward table.
//
// Likelihood (RtLikelihood::calibrated, the default). Each band's measured waveform m (its noise
// mean removed) is Gaussian about the table's expected waveform T~(theta) placed with its ground
// at the elevation g: m_b ~ N(T~(z_b - g), V(b)), with
//   V = noise_sd^2 + (r_m + h_e / K) v(T~),   v(T) = a T + c T^2,
// the shot's detector noise plus the Monte Carlo noise of the measured shot (r_m = the table's
// rays over the shot's for simulated input, 0 for real input) and of the table's expectation (K
// shots an entry, h_e the emulator's variance factor). v is fitted per band by iteratively
// reweighted least squares to the scatter of each entry's first shot about its mean (the rays'
// Poisson noise gives a T, a ray's amplitude; the ground's and crowns' whole returns, whose share
// of rays varies, give c T^2); its signal is floored at a, one ray, below which a Gaussian of the
// Poisson variance mis-scores lone rays. T~ is a local linear emulator: at each entry, the
// least-squares plane through its k nearest entries in the design's normalised coordinates
// (categorical keys equal), which averages away the entries' own Monte Carlo noise (the first
// cut compared the shot with each entry's noisy mean, so that neighbours lay tens of chi2 apart)
// and whose variance factor h_e = sum of the squared hat weights. The ground is continuous: whole
// bins s searched, and within each a sub-bin offset delta in [-1/2, 1/2] profiled on T~'s first
// order expansion T~(j - delta) = T~(j) - delta dT~/dj (a half bin left whole misplaces a
// Gaussian pulse's flank by several times the noise). The log-likelihood is
//   l = -(chi2 + sum log V) / (2 tau),
// tau the tempering that the pulse's correlation of the Monte Carlo noise across bins demands (a
// ray's return spreads over the pulse: independent bins would count each ray several times; the
// composite likelihood's curvature adjustment). tau is calibrated on the table itself: each of
// `calibration_shots` entries' first shot, displaced by a sub-bin offset, is retrieved from the
// other entries (its own mean replaced by its other shots' in the emulator), and tau, started at
// the pulse's correlation length 2 sqrt(pi) sigma_bins, is scaled until the 90th percentile of
// the varied parameters' squared standardised errors is a Gaussian's (2.706): the 90 % interval
// the product states.
//
// The first cut's likelihood (RtLikelihood::constant_sd), kept for comparison: sigma^2 =
// noise_sd^2 + (f peak)^2 (1/K + [simulated]) per shot, the raw entries, whole bins, tau = 1;
// its amplitude may be fitted (free_scale) for waveforms whose calibration is unknown.
//
// Search (RtSearch::two_stage, the default). The ground is found in two stages: a wide
// cross-correlation of a few entries spread over the design (the design's first 16: Halton's
// prefix covers it) over +- ground_search_m about the first guess (L2A's lowest mode, which may
// be the canopy's), every other bin; then the exact likelihood of every entry at that ground,
// the entries within prune_log_likelihood of the best kept, and those over the shifts about it,
// widened while the window's edge holds posterior mass. RtSearch::direct: every entry at every
// whole bin within search_half_width_bins of the guess (the first cut's).
//
// RtSearch::projected (the default) is two_stage whose every-entry step runs on a few principal
// components: each band's waveform is put through the variance-stabilising transform of the
// noise model, g(x) = integral of dx / sqrt(V(x)), so that (g(m) - g(T))^2 ~ (m - T)^2 / V and
// chi2 is a Euclidean distance; its `projection_components` leading components (of the
// transformed entries and their slopes, per quarter octave of detector noise, built when first
// needed) bound, up to the transform's error, every entry's chi2 profiled to first order over the
// sub-bin offset, from below and above through the parts of the shot and the entry outside the
// components, (|r_m| -+ |r_e|)^2.
// Only the entries whose lower bound lies within prune_log_likelihood + prefilter_margin of the
// best upper bound get the exact likelihood: the same cells as two_stage wherever the transform
// keeps its error within the margin (retrieval_benchmark measures how often the posteriors are
// identical), at a fraction of the cost for tables of 10^4 entries. Where more than
// max_exact_entries stay within reach (a dense table, a wide posterior), only the design's
// first of them are: the posterior of a coarser design over the same region. Tables of fewer
// than projection_min_entries are searched exactly. Where the table's window at the found ground
// overhangs the shot's waveform, its bins beyond the shot are taken as no signal and their share
// of each entry's distance is taken off both bounds (the exact chi2 counts the shot's bins).
//
// Posterior. Uniform over the table's entries (the design is the prior) and over the ground:
// w(e, s) ∝ exp(l(e, s)). Each variable's mean, sd, 5 % and 95 % come from the entries'
// marginal weights (the ground's from the shifts').
//
// Flags (rt_flag, bits): 1 the best chi2 per signal bin beyond chi2_dof_limit (the table cannot
// explain the shot), 2 more than edge_mass of the posterior in the outer edge_fraction of a
// varied range (the truth may lie outside the table), 4 the best ground at the search's edge, 8
// not run (no finite waveform, no signal), 16 the ground more than ground_offset_flag_m from the
// first guess (the guess took another return for the ground: the metres say which).
#pragma once

#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
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
  rt_ground_off_guess = 16,
};

enum class RtLikelihood { calibrated, constant_sd };
enum class RtSearch { projected, two_stage, direct };

struct RtSettings {
  double chi2_dof_limit = 4.0;
  double edge_fraction = 0.05;
  double edge_mass = 0.5;
  RtLikelihood likelihood = RtLikelihood::calibrated;
  RtSearch search = RtSearch::projected;
  // projected: the principal components kept, and the margin (log-likelihood) beyond
  // prune_log_likelihood below which an entry's lower bound sends it to the exact likelihood.
  int projection_components = 24;
  double prefilter_margin_log_likelihood = 10.0;
  // projected: the most entries given the exact likelihood (0: all). Beyond it, the design's
  // first of those the components cannot rule out: a Halton design's prefix is a coarser design
  // of the same region, so that a dense table's posterior costs what a coarser one's does. On
  // the retrieval study's reduced run (a 1500-entry table whose tempered posteriors keep some
  // 600 entries) 384 costs 1.4 times 192's CPU a shot and takes canopy height's RMSE from 3.25 to
  // 3.10 m (every entry: 2.91 m, at 4.4 times), docs/retrieval.md.
  int max_exact_entries = 384;
  // projected: tables of fewer entries are searched exactly (two_stage): there the exact
  // likelihood of every entry costs less than the components' setup, about a second.
  int projection_min_entries = 1000;
  // Whole bins searched either side of the first guess of the ground (direct); 0: 1.5 pulse
  // sigma, at least 4.
  int search_half_width_bins = 0;
  // two_stage: the wide search's half width about the first guess (m), the log-likelihood below
  // the best at which an entry is dropped, and the distance from the guess that is flagged (m).
  double ground_search_m = 15.0;
  double prune_log_likelihood = 10.0;
  double ground_offset_flag_m = 2.0;
  // The emulator's neighbours; 0: max(16, 4 (parameters + 1)); 1: the raw entries.
  int emulator_neighbours = 0;
  // The tempering tau; 0: calibrated on the table's first shots (1 where it has none).
  double tempering = 0.0;
  int calibration_shots = 200;
  // Rays a measured simulated shot traced; 0: the table's.
  double measured_rays_per_shot = 0.0;
  bool free_scale = false;  // constant_sd only
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

// One ICESat-2 land segment's photons (retrieve.hpp's PhotonSegment): their heights (m, the
// along-track slope taken out), the pulses fired over them, the background rate and the photons a
// joule of the table's return gives; a first guess of the ground (NaN: the photons' median).
struct RtPhotonShot {
  std::span<const double> heights_m;
  double pulses = 0.0, background_rate_Hz = 0.0, photons_per_J = 0.0;
  double ground_guess_m = std::numeric_limits<double>::quiet_NaN();
};

struct RtStatistic {
  double mean = 0.0, sd = 0.0, p05 = 0.0, p95 = 0.0;
};

// Mean, sd and the 5 % and 95 % points of values weighted by w, visited in increasing order
// (`order`); NaN values are left out.
RtStatistic weighted_statistic(const std::vector<double>& values, const std::vector<double>& w,
                               const std::vector<std::uint32_t>& order);

struct RtResult {
  RtStatistic canopy_height_m, cover, pai, ground_elevation_m, rhov_rhog;
  RtStatistic pgap;  // the vertical gap probability (NaN from a table that holds none)
  double chi2_min = 0.0;
  double dof = 0.0;
  std::uint8_t flag = 0;
  std::int64_t best_entry = -1;
  double best_ground_elevation_m = 0.0;  // where the best fit puts the entry's ground
  double ground_guess_m = 0.0;           // the first guess the search started from
  static RtResult none();                // NaN statistics, flag rt_not_run
};

// A shot made ready for the search: its waveforms less their noise means, its sigma per band,
// the shifts searched and the bins R compared.
struct RtPreparedShot {
  std::vector<std::vector<double>> measured;  // [band][bin]
  std::vector<double> sigma;                  // [band]
  std::vector<double> m2;                     // [band] sum of m^2 over R
  std::vector<double> noise2;                 // [band] noise_sd^2 (calibrated)
  std::vector<double> w_out;                  // [band] 1 / V where the table has no signal
  double outside = 0.0;                       // sum over R of m^2 w_out (calibrated)
  double ground_guess_m = 0.0;
  int centre_shift = 0;
  double z0_m = 0.0, dz_m = 0.0;                 // bin 0's elevation, and the step per bin
  int first_shift = 0, last_shift = 0;           // inclusive
  std::size_t region_begin = 0, region_end = 0;  // R = [begin, end) of the measured bins
  bool usable = false;
};

class RtInversion {
 public:
  // Refuses (an input error naming `table_place`) a table whose bands or bins differ from the
  // measured shots' (`band_names`, `bin_ns`).
  RtInversion(const ForwardTable& table, const RtSettings& settings);

  // Checks that shots of these bands, bin width and pulse sigma (NaN: unknown, not checked) can
  // be compared with the table.
  void check_compatible(const std::vector<std::string>& band_names, double bin_ns,
                        double pulse_sigma_ns, const std::string& table_place) const;

  RtPreparedShot prepare(const RtShot& shot) const;
  // The ground elevation of a shift.
  double ground_elevation_m(const RtPreparedShot& shot, int shift) const;
  // chi2 of one entry at one shift over R (and the amplitude used); calibrated: chi2 at the
  // profiled sub-bin offset delta, and sum log V less its value without signal.
  struct Fit {
    double chi2 = 0.0, scale = 1.0, delta = 0.0, log_det = 0.0;
  };
  Fit fit(const RtPreparedShot& shot, std::size_t entry, int shift) const;
  // calibrated: fit's chi2 as the search sums it (fit_terms: its sums regrouped into the shot's
  // correlations with the entry's weights and the entry's own totals), where fit sums it bin by
  // bin: the reference the tests hold this to.
  Fit fit_as_searched(const RtPreparedShot& shot, std::size_t entry, int shift) const;

  RtResult invert(const RtShot& shot) const;
  // A segment of photons against every entry at every ground within ground_search_m of the
  // guess (the ground found first by the design's first 16 entries, every entry then within
  // kFineSearch_m of it, widened while the window's edge holds posterior; rt_photon_search.cpp):
  // Poisson's likelihood of the photons' histogram in bins of about kPhotonBin_m, the background
  // included, each entry's expected photons its (emulated) waveform times the segment's pulses and
  // photons per joule. chi2_min is the best fit's Poisson deviance in bins of about kFitBin_m, dof
  // its expectation under the fit.
  RtResult invert_photons(const RtPhotonShot& shot) const;
  static constexpr double kPhotonBin_m = 0.15, kFitBin_m = 1.0, kFineSearch_m = 2.0;
  // The photons' tempering, calibrated on the table as the waveforms' is, for segments of these
  // pulses, photons per joule and background (rt_photon_search.cpp): entries' photons drawn
  // from their own expectation are retrieved from the other entries, and tau (at least 1, where
  // Poisson's law holds) scaled until the 90 % interval holds their parameters 90 % of the
  // time. Until it is called, 1.
  void calibrate_photons(double pulses, double photons_per_J, double background_rate_Hz);
  double photon_tempering() const { return photon_tempering_; }

  // The fitted noise model v(T) = a T + c T^2 per band (W^2), the floor of its signal, and tau.
  double variance_linear_W(std::size_t band) const { return var_linear_[band]; }
  double variance_quadratic(std::size_t band) const { return var_quadratic_[band]; }
  double tempering() const { return tempering_; }
  const std::vector<double>& emulated_W(std::size_t entry, std::size_t band) const {
    return emulated_[entry][band];
  }

 private:
  // Whether more than settings_.edge_mass of the posterior's weight (entry_weight, one an entry)
  // lies in the outer part of a varied range (edge_): the rt_table_edge flag.
  bool posterior_at_table_edge(const std::vector<double>& entry_weight) const;
  struct Cell {
    std::uint32_t entry;
    int shift;
    double log_likelihood, chi2, delta;
  };
  // Entry e's band k as the calibrated kernel reads it (the emulator's, or an override).
  struct EntryBand {
    const double* t;
    const double* slope;
    const double* curvature;
  };
  // Entry e's own bands: its emulated T~, slope and curvature (no override).
  std::vector<EntryBand> own_bands(std::size_t entry) const;
  // The transformed entries' principal components at one level of detector noise per band.
  struct Projection {
    std::size_t components = 0, width = 0;  // K, bands x bins
    // Per band: g on x = floor + (top - floor) (i / G)^2, i = 0..G, and its slope below the
    // floor and above the top.
    std::vector<std::vector<double>> g;
    std::vector<double> floor, top, slope_low, slope_high;
    std::vector<double> no_signal;    // per band g(0): where the shot has no bin, no signal
    std::vector<double> mean, basis;  // width; width x K (column k contiguous)
    std::vector<double> coords, slope_coords;   // entries x K
    std::vector<double> residual, slope_norm2;  // |r_e|, |c'_e|^2 per entry
    std::vector<double> scale, log_det;         // chi2 scale rho_ref / rho_e, sum log V
    // Per entry and band, the prefix sums over the bins of (g(0) - y_e)^2, y_e the transformed
    // entry ((bins + 1) a band): what a window's bins beyond the shot's add to the distance
    // when the shot is taken there as 0 (no signal), which the exact chi2 does not count.
    std::vector<double> beyond_prefix;
    double transform(std::size_t band, double x) const;
  };
  const Projection& projection(const RtPreparedShot& shot) const;
  std::unique_ptr<Projection> build_projection(const std::vector<double>& noise2) const;
  // The entries whose projected bounds leave them within reach of the best at `shift` (all
  // entries, `ok` false, where the table's window at that shift holds none of the shot's bins).
  std::vector<std::size_t> prefilter(const RtPreparedShot& shot, int shift, std::int64_t excluded,
                                     bool* ok) const;
  // (the entry's value of a varied range - the posterior's mean) / its sd under these weights
  // (one an entry): the tempering calibrations' measure.
  double standardised_error(const std::vector<double>& weight, std::size_t parameter,
                            std::size_t entry) const;
  void build_emulator();
  void fit_noise_model();
  void build_variances();
  void calibrate_tempering();
  RtPreparedShot prepare_window(const RtShot& shot, int centre, int half) const;
  Fit fit_calibrated(const RtPreparedShot& shot, std::size_t entry, int shift,
                     const EntryBand* bands) const;
  // fit_calibrated's terms of one entry for one shot's detector noise, kept for every shift the
  // search tries (16 an entry on average, up to a few hundred): per band over the entry's
  // support, the weights w = 1 / V and their products with the emulated waveform, its slope and
  // curvature, which the shot is correlated with, and the sums that do not hold the shot; and
  // sum log V.
  struct EntryTerms {
    struct Band {
      long long begin = 0, end = 0;  // the entry's support, n = end - begin bins
      const double *t = nullptr, *slope = nullptr, *curvature = nullptr;  // from its support
      // Per bin of the support, interleaved (one stream for the kernel to read): w, T~ w, T~' w,
      // T~'' w (4 n values, not zeroed).
      std::unique_ptr<double[]> data;
      // Over the whole support (the range at nearly every shift): T~^2 w, T~ T~' w, T~ T~'' w,
      // T~'^2 w, T~' T~'' w, T~''^2 w.
      double total[6] = {};
      std::size_t n() const { return static_cast<std::size_t>(end - begin); }
    };
    std::vector<Band> bands;
    double log_det = 0.0;
  };
  // The six sums of Band::total over the support's bins [i0, i1).
  static void entry_sums(const EntryTerms::Band& band, std::size_t i0, std::size_t i1,
                         double sums[6]);
  // The shot's m^2 and m per bin, interleaved, and the prefix sums of m^2, per band: the other
  // half of the correlations.
  struct ShotTerms {
    std::vector<std::vector<double>> m2_m, prefix_m2;
  };
  ShotTerms shot_terms(const RtPreparedShot& shot) const;
  // Entry `entry`'s terms for a shot of detector noise variances `noise2` (per band).
  void entry_terms(const std::vector<double>& noise2, std::size_t entry, const EntryBand* bands,
                   EntryTerms& terms) const;
  // fit_calibrated from the terms: the same chi2 to rounding (its sums regrouped), its per-bin
  // work two pairs of products instead of a division and a dozen operations.
  Fit fit_terms(const RtPreparedShot& shot, const ShotTerms& shot_terms, const EntryTerms& terms,
                int shift) const;
  // The fit from its sums over the bins: chi2 profiled over the sub-bin offset delta.
  static Fit profile_delta(double a, double bsum, double c, double cf, double cg, double ch,
                           double log_det);
  double log_det(const std::vector<double>& noise2, std::size_t entry) const;
  // The cells searched (calibrated); `excluded` an entry left out (the calibration's), `override`
  // bands per entry where non-null; `shared` (where non-null) every entry's terms for this
  // shot's noise, used where an entry has no override (the calibration's shots, all without
  // detector noise, share them).
  std::vector<Cell> search(const RtPreparedShot& shot, std::int64_t excluded,
                           const std::vector<const EntryBand*>& override_bands, bool* at_edge,
                           const std::vector<EntryTerms>* shared = nullptr) const;
  RtResult summarise(const RtPreparedShot& shot, const std::vector<Cell>& cells,
                     bool at_edge) const;
  // invert_photons with entry `excluded` left out, grounds within search_m of the guess, the
  // log-likelihood divided by `tempering`; each entry's best log-likelihood (untempered) into
  // `entry_best` when given.
  RtResult search_photons(const RtPhotonShot& shot, std::int64_t excluded, double search_m,
                          double tempering, std::vector<double>* entry_best) const;
  // The entries' truths' statistics under these weights, into r (truths_' order: height, cover,
  // pai, rhov_rhog, pgap).
  void entry_statistics(const std::vector<double>& entry_weight, RtResult& r) const;

  const ForwardTable& table_;
  RtSettings settings_;
  double mc_relative_sd_;
  // Per entry and band: the bins [support_begin, support_end) above 1e-4 of the peak, and the
  // prefix sums of T^2.
  std::vector<std::vector<std::size_t>> support_begin_, support_end_;
  std::vector<std::vector<std::vector<double>>> prefix_tt_;
  // The entries' truths (height, cover, pai, rhov_rhog, pgap: the table's, or NaN where it
  // holds none) and their indices sorted by each, for the quantiles.
  std::vector<const std::vector<double>*> truths_;
  std::vector<double> pgap_true_;
  std::vector<std::vector<std::uint32_t>> sorted_;
  // Per entry: whether it lies in the outer edge of a varied range, low or high, per parameter.
  std::vector<std::vector<std::uint8_t>> edge_;
  // Calibrated: per entry and band the emulated T~ and its slope per bin, V's signal part u
  // and 1/u, sum log(u / u_out) without detector noise and on a grid of noise variances; the
  // emulator's weights (neighbour, weight) and variance factor.
  std::vector<std::vector<std::vector<double>>> emulated_, slope_, curvature_, signal_var_,
      inv_signal_var_;
  std::vector<std::vector<std::vector<double>>> log_det_grid_;
  std::vector<std::vector<std::pair<std::uint32_t, double>>> smoother_;
  std::vector<double> leverage_;
  std::vector<double> var_linear_, var_quadratic_, signal_floor_W_, out_var_;
  double measured_factor_ = 1.0;  // r_m
  double tempering_ = 1.0;
  double photon_tempering_ = 1.0;
  // The projections, one per quarter octave of each band's detector noise.
  mutable std::mutex projections_mutex_;
  mutable std::map<std::vector<int>, std::unique_ptr<const Projection>> projections_;
};

}  // namespace glaswave
