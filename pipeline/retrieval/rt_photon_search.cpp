// rt on ICESat-2's photons: a land segment's photon heights against every entry of the table
// under Poisson's law, the background included (rt_inversion.hpp, invert_photons).
//
// The segment's photons are counted in bins of D (about kPhotonBin_m: whole table bins, m of
// them) over the heights any entry can reach from a ground within ground_search_m of the guess.
// Entry e placed with its ground at shift s expects in bin b
//   mu_b = S_e[b - s] + B,  S_e[c] = N q tau sum_{j in c} T_e[j],  B = N r 2 D / c,
// N the pulses, q the photons a joule gives, tau the table's bin, T_e its waveform (W; the
// emulated one where the calibrated likelihood built it, which averages the entries' own Monte
// Carlo noise), r the background rate. Poisson's log-likelihood of the counts k_b, less what no
// entry changes, is
//   l(e, s) = sum_c k_{c+s} log(1 + S_e[c] / B_e) - sum_c S_e[c] + K log B_e - n B_e,
// K the photons and n the bins counted; B_e = max(B, 1e-4 of S_e's peak), a floor where a
// segment has no background, so that a photon where an entry expects none does not rule it out
// altogether (the entry's support ends at 1e-4 of its peak, as the waveform search's does).
// The grounds tried lie a table bin apart: each of the m phases of the counts' bins, a table bin
// lower than the last, has its shifts (the phases after the first for the entries the first
// leaves within reach). The posterior is w(e, s) ~ exp(l / tau), the design the prior. Photons
// are independent draws, but a segment's forest is none of the table's: tau is calibrated on
// the table (calibrate_photons), as the waveforms' is.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "core/random.hpp"
#include "core/samplers.hpp"
#include "pipeline/retrieval/rt_inversion.hpp"

namespace glaswave {
namespace {

// 2 (k ln(k / mu) - (k - mu)): Poisson's deviance of k counts expecting mu.
double poisson_deviance(double k, double mu) {
  return 2.0 * ((k > 0.0 ? k * std::log(k / mu) : 0.0) - (k - mu));
}

// Its mean over k ~ Poisson(mu): summed over k to 12 sd beyond mu, or 1 + 1 / (6 mu) (the
// series' first terms) where mu is large.
double expected_poisson_deviance(double mu) {
  if (mu > 50.0) return 1.0 + 1.0 / (6.0 * mu);
  double p = std::exp(-mu), sum = 0.0;
  const int last = static_cast<int>(mu + 12.0 * std::sqrt(mu) + 12.0);
  for (int k = 0; k <= last; ++k) {
    sum += p * poisson_deviance(k, mu);
    p *= mu / (k + 1);
  }
  return sum;
}

}  // namespace

RtResult RtInversion::invert_photons(const RtPhotonShot& shot) const {
  return search_photons(shot, -1, settings_.ground_search_m, photon_tempering_, nullptr);
}

RtResult RtInversion::search_photons(const RtPhotonShot& shot, std::int64_t excluded,
                                     double search_m, double tempering,
                                     std::vector<double>* entry_best_out) const {
  constexpr double c_m_per_s = 299792458.0;
  const std::size_t entries = table_.entries(), bins = table_.height_m.size();
  if (entries == 0 || bins < 2 || shot.heights_m.empty() || !(shot.pulses > 0.0) ||
      !(shot.photons_per_J > 0.0) || !std::isfinite(shot.photons_per_J) ||
      !(shot.background_rate_Hz >= 0.0))
    return RtResult::none();
  const double dz_table_m = table_.height_m[0] - table_.height_m[1];
  const std::size_t per_bin =
      static_cast<std::size_t>(std::max(1.0, std::round(kPhotonBin_m / dz_table_m)));
  const double bin_m = static_cast<double>(per_bin) * dz_table_m;
  const std::size_t coarse = (bins + per_bin - 1) / per_bin;
  double guess = shot.ground_guess_m;
  if (!std::isfinite(guess)) {
    std::vector<double> h(shot.heights_m.begin(), shot.heights_m.end());
    std::nth_element(h.begin(), h.begin() + static_cast<std::ptrdiff_t>(h.size() / 2), h.end());
    guess = h[h.size() / 2];
  }
  const int half = std::max(1, static_cast<int>(std::ceil(search_m / bin_m)));
  const int shifts = 2 * half + 1;
  const std::size_t counted = static_cast<std::size_t>(2 * half) + coarse;
  const int phases = static_cast<int>(per_bin);
  // The top of the counts' bin 0 at phase 0: where the table's top bin's top lies with the
  // ground at the guess, half the shifts higher. Phase p lowers the bins by p table bins, so that
  // the grounds tried are the table's bins apart: ground(s, p) = top - (s per_bin + p) dz - h0 -
  // dz / 2, the fine index s per_bin + p.
  const double top_m = guess + table_.height_m[0] + 0.5 * dz_table_m + half * bin_m;
  const auto counts = [&](int phase) {
    std::vector<double> k(counted, 0.0);
    const double top = top_m - phase * dz_table_m;
    for (const double h : shot.heights_m) {
      const double b = std::floor((top - h) / bin_m);
      if (b >= 0.0 && b < static_cast<double>(counted)) k[static_cast<std::size_t>(b)] += 1.0;
    }
    return k;
  };
  // Every phase's likelihood over the same window, the union of their bins: its photons outside
  // a phase's bins meet no entry's signal there, and count as background alone.
  const double window_bins =
      static_cast<double>(counted) + static_cast<double>(phases - 1) / phases;
  double photons = 0.0;
  for (const double h : shot.heights_m) photons += h <= top_m && h > top_m - window_bins * bin_m;
  const double background = shot.pulses * shot.background_rate_Hz * 2.0 * bin_m / c_m_per_s;
  const double per_W = shot.pulses * shot.photons_per_J * table_.bin_ns * 1e-9;
  const int fine = shifts * phases;
  const auto ground_of = [&](int f) {
    return top_m - f * dz_table_m - table_.height_m[0] - 0.5 * dz_table_m;
  };
  const auto expected_of = [&](std::size_t e, std::vector<double>& expected) {
    const std::vector<double>& t = emulated_.empty() ? table_.waveform_W[e][0] : emulated_[e][0];
    std::fill(expected.begin(), expected.end(), 0.0);
    for (std::size_t j = 0; j < bins; ++j) expected[j / per_bin] += std::max(0.0, t[j]) * per_W;
  };
  // Each entry's terms, made when first needed: its floor, its bins of signal with their
  // log(1 + S / B) (most of an entry's bins expect nothing), and what no shift changes.
  struct Terms {
    std::vector<std::pair<std::uint32_t, double>> gain;
    double floor = 0.0, constant = 0.0;  // a floor of 0: not made yet (a made one is positive)
  };
  std::vector<Terms> terms(entries);
  std::vector<double> expected(coarse);
  const auto terms_of = [&](std::size_t e) -> const Terms& {
    Terms& t = terms[e];
    if (t.floor > 0.0) return t;
    expected_of(e, expected);
    const double peak = *std::max_element(expected.begin(), expected.end());
    const double total = std::accumulate(expected.begin(), expected.end(), 0.0);
    t.floor = std::max({background, 1e-4 * peak, 1e-300});
    for (std::size_t c = 0; c < coarse; ++c)
      if (expected[c] > 0.0)
        t.gain.push_back({static_cast<std::uint32_t>(c), std::log1p(expected[c] / t.floor)});
    t.constant = photons * std::log(t.floor) - window_bins * t.floor - total;
    return t;
  };
  std::vector<std::vector<double>> k_of(phases);
  for (int phase = 0; phase < phases; ++phase) k_of[phase] = counts(phase);

  std::vector<double> log_likelihood(entries * fine), entry_best(entries);
  std::vector<double> sums(shifts);
  double best = -std::numeric_limits<double>::infinity();
  std::size_t best_cell = 0;
  // Entry e at phase `phase` and the shifts [lo, hi]: every shift at once, bin by bin of its
  // signal (a loop the compiler vectorises).
  const auto evaluate = [&](std::size_t e, int phase, int lo, int hi) {
    const Terms& t = terms_of(e);
    const std::vector<double>& k = k_of[phase];
    std::fill(sums.begin() + lo, sums.begin() + hi + 1, 0.0);
    for (const auto& [c, g] : t.gain) {
      const double* kc = k.data() + c;
      for (int s = lo; s <= hi; ++s) sums[s] += kc[s] * g;
    }
    for (int s = lo; s <= hi; ++s) {
      const double l = sums[s] + t.constant;
      const std::size_t cell = e * fine + static_cast<std::size_t>(s * phases + phase);
      log_likelihood[cell] = l;
      entry_best[e] = std::max(entry_best[e], l);
      if (l > best) {
        best = l;
        best_cell = cell;
      }
    }
  };
  const auto searched = [&](std::size_t e) { return static_cast<std::int64_t>(e) != excluded; };
  // The ground first from the design's first 16 entries (Halton's prefix covers the design) at
  // every shift; then every entry within kFineSearch_m of it, widened while the window's edge
  // holds more than 1e-3 of the posterior.
  const int reach = std::max(1, static_cast<int>(std::ceil(kFineSearch_m / bin_m)));
  int lo = 0, hi = shifts - 1;
  if (shifts > 2 * reach + 1) {
    std::fill(entry_best.begin(), entry_best.end(), -std::numeric_limits<double>::infinity());
    for (std::size_t e = 0; e < std::min<std::size_t>(16, entries); ++e)
      if (searched(e)) evaluate(e, 0, 0, shifts - 1);
    if (!std::isfinite(best)) return RtResult::none();
    const int centre = static_cast<int>(best_cell % fine) / phases;
    lo = std::max(0, centre - reach);
    hi = std::min(shifts - 1, centre + reach);
  }
  std::vector<double> entry_weight(entries), shift_weight(fine);
  for (;;) {
    // Phase 0 for every entry; the other phases for the entries phase 0 leaves within reach of
    // its best (the sub-bin placement moves every entry's likelihood alike, by up to a hundred
    // where hundreds of ground photons lie within a pulse sigma).
    std::fill(log_likelihood.begin(), log_likelihood.end(),
              -std::numeric_limits<double>::infinity());
    std::fill(entry_best.begin(), entry_best.end(), -std::numeric_limits<double>::infinity());
    best = -std::numeric_limits<double>::infinity();
    for (std::size_t e = 0; e < entries; ++e)
      if (searched(e)) evaluate(e, 0, lo, hi);
    const double phase0_best = best;
    const double reach_l =
        tempering * (settings_.prune_log_likelihood + settings_.prefilter_margin_log_likelihood);
    for (int phase = 1; phase < phases; ++phase)
      for (std::size_t e = 0; e < entries; ++e)
        if (searched(e) && entry_best[e] >= phase0_best - reach_l) evaluate(e, phase, lo, hi);
    if (!std::isfinite(best)) return RtResult::none();
    std::fill(entry_weight.begin(), entry_weight.end(), 0.0);
    std::fill(shift_weight.begin(), shift_weight.end(), 0.0);
    for (std::size_t e = 0; e < entries; ++e)
      for (int f = lo * phases; f < (hi + 1) * phases; ++f) {
        const double w = std::exp((log_likelihood[e * fine + f] - best) / tempering);
        entry_weight[e] += w;
        shift_weight[f] += w;
      }
    if (lo == 0 && hi == shifts - 1) break;
    double total = 0.0, edge = 0.0;
    for (int f = lo * phases; f < (hi + 1) * phases; ++f) total += shift_weight[f];
    for (int p = 0; p < phases; ++p)
      edge += (lo > 0 ? shift_weight[lo * phases + p] : 0.0) +
              (hi < shifts - 1 ? shift_weight[hi * phases + p] : 0.0);
    if (edge <= 1e-3 * total) break;
    lo = std::max(0, lo - reach);
    hi = std::min(shifts - 1, hi + reach);
  }
  if (entry_best_out) *entry_best_out = entry_best;
  RtResult r;
  entry_statistics(entry_weight, r);
  std::vector<double> grounds(fine);
  std::vector<std::uint32_t> order(fine);
  for (int f = 0; f < fine; ++f) {
    grounds[f] = ground_of(f);
    order[f] = static_cast<std::uint32_t>(fine - 1 - f);  // the last is the lowest
  }
  r.ground_elevation_m = weighted_statistic(grounds, shift_weight, order);
  const std::size_t top_entry = best_cell / fine;
  const int top_fine = static_cast<int>(best_cell % fine);
  const int top_shift = top_fine / phases;
  r.best_entry = static_cast<std::int64_t>(top_entry);
  r.best_ground_elevation_m = ground_of(top_fine);
  r.ground_guess_m = guess;
  // The best fit's deviance in bins of about kFitBin_m, over its expectation under the fit:
  // sparse counts' deviance is not chi-squared (a bin expecting 0.07 background photons adds 0.37
  // on average), and wider bins let a wrong scale show (half the photons expected: 0.6 a photon).
  const std::vector<double>& k = k_of[top_fine % phases];
  expected_of(top_entry, expected);
  const std::size_t per_fit_bin =
      static_cast<std::size_t>(std::max(1.0, std::round(kFitBin_m / bin_m)));
  double deviance = 0.0, expected_deviance = 0.0;
  for (std::size_t from = 0; from < counted; from += per_fit_bin) {
    double observed = 0.0, mu = 0.0;
    for (std::size_t b = from; b < std::min(counted, from + per_fit_bin); ++b) {
      const long long c = static_cast<long long>(b) - top_shift;
      mu += (c >= 0 && c < static_cast<long long>(coarse) ? expected[c] : 0.0) +
            terms[top_entry].floor;
      observed += k[b];
    }
    deviance += poisson_deviance(observed, mu);
    expected_deviance += expected_poisson_deviance(mu);
  }
  r.chi2_min = deviance;
  r.dof = expected_deviance;
  if (r.chi2_min / r.dof > settings_.chi2_dof_limit) r.flag |= rt_misfit;
  if (posterior_at_table_edge(entry_weight)) r.flag |= rt_table_edge;
  if (top_shift == 0 || top_shift == shifts - 1) r.flag |= rt_ground_search_edge;
  if (std::abs(r.ground_elevation_m.mean - guess) > settings_.ground_offset_flag_m)
    r.flag |= rt_ground_off_guess;
  return r;
}

// The cases: every entry inside the design's ranges (none in an outer edge_fraction), at most
// kCases spread over the table. Case c's photons are drawn (keyed by the table's seed and the
// entry) from its other shots' mean (its first shot left out, which the emulator of its
// neighbours still holds: a little of the truth leaks), its ground at 0, the background over
// the heights searched; it is retrieved from the other entries with grounds within 2 m. Each
// case keeps every entry's best log-likelihood, from which the posterior's mean and sd of each
// varied range follow for any tau (the shifts profiled, not summed: the grounds' spread is a
// small part of an entry's weight); tau is the smallest at least 1 that brings the 90th
// percentile of the squared standardised errors to a Gaussian's, 2.706.
void RtInversion::calibrate_photons(double pulses, double photons_per_J,
                                    double background_rate_Hz) {
  constexpr std::size_t kCases = 100;
  constexpr double kSearch_m = 2.0, kP90 = 2.705543454095404;
  const ForwardTable& t = table_;
  const std::size_t entries = t.entries(), bins = t.height_m.size();
  photon_tempering_ = 1.0;
  if (entries < 8 || bins < 2 || !(pulses > 0.0) || !(photons_per_J > 0.0)) return;
  std::vector<std::size_t> ranges;
  for (std::size_t q = 0; q < t.parameters.size(); ++q)
    if (t.parameters[q].is_range() && t.parameters[q].high > t.parameters[q].low)
      ranges.push_back(q);
  if (ranges.empty()) return;
  std::vector<std::size_t> cases;
  for (std::size_t i = 0; i < std::min(kCases, entries); ++i) {
    const std::size_t e = i * entries / std::min(kCases, entries);
    bool inside = true;
    for (std::size_t q = 0; q < t.parameters.size(); ++q) inside = inside && edge_[e][q] == 0;
    if (inside) cases.push_back(e);
  }
  if (cases.size() < 5) return;
  const double dz_m = t.height_m[0] - t.height_m[1];
  const double per_W = pulses * photons_per_J * t.bin_ns * 1e-9;
  const double k_shots = static_cast<double>(t.shots_per_entry);
  std::vector<std::vector<double>> best_of(cases.size());
  tbb::parallel_for(std::size_t{0}, cases.size(), [&](std::size_t i) {
    const std::size_t e = cases[i];
    RandomStream random(t.seed, e, 0, RandomPurpose::photon_calibration);
    const bool apart = k_shots >= 2.0 && t.shot0_W.size() == entries && !t.shot0_W[e].empty();
    std::vector<double> heights;
    for (std::size_t j = 0; j < bins; ++j) {
      const double mean_W =
          apart ? (k_shots * t.waveform_W[e][0][j] - t.shot0_W[e][0][j]) / (k_shots - 1.0)
                : t.waveform_W[e][0][j];
      const double n = poisson(random, std::max(0.0, mean_W) * per_W);
      for (double k = 0.0; k < n; k += 1.0)
        heights.push_back(t.height_m[j] + (random.uniform() - 0.5) * dz_m);
    }
    const double low = t.height_m.back() - kSearch_m, high = t.height_m.front() + kSearch_m;
    const double background =
        poisson(random, pulses * background_rate_Hz * 2.0 * (high - low) / 299792458.0);
    for (double k = 0.0; k < background; k += 1.0)
      heights.push_back(low + random.uniform() * (high - low));
    if (heights.empty()) return;
    RtPhotonShot shot{heights, pulses, background_rate_Hz, photons_per_J, 0.0};
    search_photons(shot, static_cast<std::int64_t>(e), kSearch_m, 1.0, &best_of[i]);
  });
  // The 90th percentile of z^2 over the cases and ranges at tau.
  const auto q90 = [&](double tau) {
    std::vector<double> z2;
    std::vector<double> w(entries);
    for (std::size_t i = 0; i < cases.size(); ++i) {
      const std::vector<double>& l = best_of[i];
      if (l.size() != entries) continue;
      const double top = *std::max_element(l.begin(), l.end());
      if (!std::isfinite(top)) continue;
      for (std::size_t e = 0; e < entries; ++e)
        w[e] = std::isfinite(l[e]) ? std::exp((l[e] - top) / tau) : 0.0;
      for (std::size_t q : ranges) {
        const double z = standardised_error(w, q, cases[i]);
        z2.push_back(z * z);
      }
    }
    if (z2.size() < 5) return 0.0;
    std::sort(z2.begin(), z2.end());
    return z2[z2.size() * 9 / 10];
  };
  if (q90(1.0) <= kP90) return;
  // z^2 falls as tau widens the posterior: bisection in log tau over [1, 1e4].
  double low = 1.0, high = 1e4;
  if (q90(high) > kP90) {
    photon_tempering_ = high;
    return;
  }
  for (int round = 0; round < 40 && high / low > 1.01; ++round) {
    const double mid = std::sqrt(low * high);
    (q90(mid) > kP90 ? low : high) = mid;
  }
  photon_tempering_ = high;
}

}  // namespace glaswave
