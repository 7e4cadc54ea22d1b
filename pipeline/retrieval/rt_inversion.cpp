// The rt inversion: the likelihood of a measured waveform under each table entry at each shift,
// the search over the entries and the ground, the posterior's statistics and its flags
// (rt_inversion.hpp says how). What is learnt from the table before any shot is in
// rt_table_model.cpp, the projected search's components in rt_projected_search.cpp.
#include "pipeline/retrieval/rt_inversion.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <numeric>

#include "core/error.hpp"

namespace glaswave {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Two doubles as one SSE2 register (GCC's and Clang's vector extension): fit_terms's sums.
using Pair = double __attribute__((vector_size(16)));
Pair load_pair(const double* p) {
  Pair v;
  std::memcpy(&v, p, sizeof v);  // unaligned
  return v;
}

RtStatistic no_statistic() { return {kNaN, kNaN, kNaN, kNaN}; }

}  // namespace

// A quantile is the first value at which the cumulative weight reaches it.
RtStatistic weighted_statistic(const std::vector<double>& values, const std::vector<double>& w,
                               const std::vector<std::uint32_t>& order) {
  double total = 0.0, sum = 0.0, sum2 = 0.0;
  for (std::uint32_t i : order) {
    if (std::isnan(values[i]) || w[i] <= 0.0) continue;
    total += w[i];
    sum += w[i] * values[i];
  }
  if (!(total > 0.0)) return no_statistic();
  const double mean = sum / total;
  for (std::uint32_t i : order)
    if (!std::isnan(values[i]) && w[i] > 0.0)
      sum2 += w[i] * (values[i] - mean) * (values[i] - mean);
  RtStatistic s{mean, std::sqrt(sum2 / total), kNaN, kNaN};
  double cumulative = 0.0;
  for (std::uint32_t i : order) {
    if (std::isnan(values[i]) || w[i] <= 0.0) continue;
    cumulative += w[i];
    if (std::isnan(s.p05) && cumulative >= 0.05 * total) s.p05 = values[i];
    if (cumulative >= 0.95 * total) {
      s.p95 = values[i];
      break;
    }
  }
  if (std::isnan(s.p95)) s.p95 = s.p05;
  return s;
}

RtResult RtResult::none() {
  RtResult r;
  r.canopy_height_m = r.cover = r.pai = r.ground_elevation_m = r.rhov_rhog = r.pgap =
      no_statistic();
  r.chi2_min = r.dof = r.ground_guess_m = r.best_ground_elevation_m = kNaN;
  r.flag = rt_not_run;
  return r;
}

void RtInversion::check_compatible(const std::vector<std::string>& band_names, double bin_ns,
                                   double pulse_sigma_ns, const std::string& table_place) const {
  std::string mine, theirs;
  for (const std::string& b : table_.band_names) mine += (mine.empty() ? "" : ",") + b;
  for (const std::string& b : band_names) theirs += (theirs.empty() ? "" : ",") + b;
  if (mine != theirs)
    throw input_error(table_place, "the table's bands (" + mine + ") are not the shots' (" +
                                       theirs + "): build it with the shots' sensor");
  if (!(std::abs(bin_ns - table_.bin_ns) <= 1e-6 * table_.bin_ns))
    throw input_error(table_place, "the table's bins of " + std::to_string(table_.bin_ns) +
                                       " ns are not the shots' " + std::to_string(bin_ns) +
                                       " ns: build it with the shots' sensor");
  // Another sensor's pulse (a GLAS table for GEDI shots: 5 against 6.625 ns) fits every shot
  // badly and silently.
  if (std::isfinite(pulse_sigma_ns) &&
      !(std::abs(pulse_sigma_ns - table_.pulse_sigma_ns) <= 1e-6 * table_.pulse_sigma_ns))
    throw input_error(table_place, "the table's pulse sigma of " +
                                       std::to_string(table_.pulse_sigma_ns) +
                                       " ns is not the shots' " + std::to_string(pulse_sigma_ns) +
                                       " ns: build it with the shots' sensor");
}

RtPreparedShot RtInversion::prepare(const RtShot& shot) const {
  const double sigma_bins = table_.pulse_sigma_ns / table_.bin_ns;
  const int direct_half = settings_.search_half_width_bins > 0
                              ? settings_.search_half_width_bins
                              : std::max(4, static_cast<int>(std::ceil(1.5 * sigma_bins)));
  return prepare_window(shot, std::numeric_limits<int>::min(), direct_half);
}

// `centre` min(): about the first guess; `half` the shifts either side, or (two_stage) the wide
// search's.
RtPreparedShot RtInversion::prepare_window(const RtShot& shot, int centre, int half) const {
  RtPreparedShot p;
  const std::size_t bands = table_.bands();
  if (shot.waveform.size() != bands || shot.waveform.empty()) return p;
  const std::size_t n = shot.waveform[0].size();
  if (n < 2) return p;
  p.z0_m = shot.axis.elev_bin0_m;
  p.dz_m = (shot.axis.elev_lastbin_m - shot.axis.elev_bin0_m) / static_cast<double>(n - 1);
  if (!std::isfinite(p.dz_m) || p.dz_m >= 0.0) return p;
  const bool calibrated = settings_.likelihood == RtLikelihood::calibrated;
  const double f2 = mc_relative_sd_ * mc_relative_sd_ *
                    (1.0 / std::max<double>(1.0, static_cast<double>(table_.shots_per_entry)) +
                     (settings_.measured_is_simulated ? 1.0 : 0.0));
  double peak0 = 0.0;
  for (std::size_t k = 0; k < bands; ++k) {
    if (shot.waveform[k].size() != n) return p;
    std::vector<double> m(n);
    double peak = 0.0;
    for (std::size_t b = 0; b < n; ++b) {
      m[b] = shot.waveform[k][b] - shot.noise_mean_W[k];
      if (!std::isfinite(m[b])) return p;
      peak = std::max(peak, m[b]);
    }
    if (k == 0) peak0 = peak;
    const double noise = std::isfinite(shot.noise_sd_W[k]) ? shot.noise_sd_W[k] : 0.0;
    p.noise2.push_back(noise * noise);
    p.sigma.push_back(std::sqrt(noise * noise + f2 * peak * peak));
    if (!calibrated && !(p.sigma.back() > 0.0)) return p;
    if (calibrated) p.w_out.push_back(1.0 / (noise * noise + out_var_[k]));
    p.measured.push_back(std::move(m));
  }
  if (!(peak0 > 0.0)) return p;
  const double sigma_bins = table_.pulse_sigma_ns / table_.bin_ns;
  double guess = shot.ground_guess_m;
  if (!std::isfinite(guess)) {
    std::size_t lowest = 0;
    for (std::size_t b = 0; b < n; ++b)
      if (p.measured[0][b] > 0.05 * peak0) lowest = b;
    guess = p.z0_m + (static_cast<double>(lowest) - 2.45 * sigma_bins) * p.dz_m;
  }
  p.ground_guess_m = guess;
  const double h0 = table_.height_m.front();
  p.centre_shift = centre != std::numeric_limits<int>::min()
                       ? centre
                       : static_cast<int>(std::lround((guess + h0 - p.z0_m) / p.dz_m));
  p.first_shift = p.centre_shift - half;
  p.last_shift = p.centre_shift + half;
  const long long bins = static_cast<long long>(table_.height_m.size());
  const long long begin = std::max<long long>(0, p.first_shift);
  const long long end = std::min<long long>(static_cast<long long>(n), p.last_shift + bins);
  if (begin >= end) return p;
  p.region_begin = static_cast<std::size_t>(begin);
  p.region_end = static_cast<std::size_t>(end);
  for (std::size_t k = 0; k < p.measured.size(); ++k) {
    double m2 = 0.0;
    for (std::size_t b = p.region_begin; b < p.region_end; ++b)
      m2 += p.measured[k][b] * p.measured[k][b];
    p.m2.push_back(m2);
    if (calibrated) p.outside += m2 * p.w_out[k];
  }
  p.usable = true;
  return p;
}

double RtInversion::ground_elevation_m(const RtPreparedShot& shot, int shift) const {
  return shot.z0_m + shift * shot.dz_m - table_.height_m.front();
}

RtInversion::Fit RtInversion::fit(const RtPreparedShot& shot, std::size_t entry, int shift) const {
  if (settings_.likelihood == RtLikelihood::calibrated) {
    return fit_calibrated(shot, entry, shift, own_bands(entry).data());
  }
  // Per band, over R: sum (m - a T)^2 = M2 - 2 a C + a^2 TT, where the table's bin j meets the
  // measured bin j + shift; T is 0 beyond the table's bins.
  const long long n = static_cast<long long>(shot.measured[0].size());
  const long long bins = static_cast<long long>(table_.height_m.size());
  double m2w = 0.0, cw = 0.0, ttw = 0.0;  // each weighted by 1 / sigma^2
  for (std::size_t k = 0; k < shot.measured.size(); ++k) {
    const std::vector<double>& m = shot.measured[k];
    const std::vector<double>& t = table_.waveform_W[entry][k];
    const double inv = 1.0 / (shot.sigma[k] * shot.sigma[k]);
    const double m2 = shot.m2[k];
    const long long j0 = std::max<long long>({0, static_cast<long long>(shot.region_begin) - shift,
                                              static_cast<long long>(support_begin_[entry][k])});
    const long long j1 = std::min<long long>({bins, static_cast<long long>(shot.region_end) - shift,
                                              static_cast<long long>(support_end_[entry][k])});
    double c = 0.0;
    for (long long j = j0; j < j1; ++j) c += m[j + shift] * t[j];
    // T^2 over the table's bins inside R (the whole support when R holds it).
    const long long a0 = std::max<long long>(0, static_cast<long long>(shot.region_begin) - shift);
    const long long a1 =
        std::min<long long>({bins, static_cast<long long>(shot.region_end) - shift, n - shift});
    const double tt = a1 > a0 ? prefix_tt_[entry][k][a1] - prefix_tt_[entry][k][a0] : 0.0;
    m2w += m2 * inv;
    cw += c * inv;
    ttw += tt * inv;
  }
  Fit f;
  if (settings_.free_scale) f.scale = ttw > 0.0 ? std::max(0.0, cw / ttw) : 0.0;
  f.chi2 = m2w - 2.0 * f.scale * cw + f.scale * f.scale * ttw;
  return f;
}

std::vector<RtInversion::EntryBand> RtInversion::own_bands(std::size_t entry) const {
  std::vector<EntryBand> bands;
  for (std::size_t k = 0; k < table_.bands(); ++k)
    bands.push_back(
        {emulated_[entry][k].data(), slope_[entry][k].data(), curvature_[entry][k].data()});
  return bands;
}

RtInversion::Fit RtInversion::fit_as_searched(const RtPreparedShot& shot, std::size_t entry,
                                              int shift) const {
  EntryTerms terms;
  entry_terms(shot.noise2, entry, own_bands(entry).data(), terms);
  return fit_terms(shot, shot_terms(shot), terms, shift);
}

// Over R: chi2 = sum m^2 w_out + sum over the entry's support of [(m - T)^2 w - m^2 w_out],
// w = 1 / (n^2 + u); with T(j - delta) = T - delta T', chi2(delta) = A + 2 delta B + delta^2 C,
// minimised over delta in [-1/2, 1/2]. The reference: search uses fit_terms, the same sums
// regrouped.
RtInversion::Fit RtInversion::fit_calibrated(const RtPreparedShot& shot, std::size_t entry,
                                             int shift, const EntryBand* bands) const {
  double a = shot.outside, bsum = 0.0, c = 0.0, cf = 0.0, cg = 0.0, ch = 0.0;
  for (std::size_t k = 0; k < shot.measured.size(); ++k) {
    const double* m = shot.measured[k].data();
    const double* t = bands[k].t;
    const double* d = bands[k].slope;
    const double* e2 = bands[k].curvature;
    const long long j0 = std::max<long long>(static_cast<long long>(shot.region_begin) - shift,
                                             static_cast<long long>(support_begin_[entry][k]));
    const long long j1 = std::min<long long>(static_cast<long long>(shot.region_end) - shift,
                                             static_cast<long long>(support_end_[entry][k]));
    const double w_out = shot.w_out[k];
    double sa = 0.0, sb = 0.0, sc = 0.0, sf = 0.0, sg = 0.0, sh = 0.0;
    if (shot.noise2[k] > 0.0) {
      const double n2 = shot.noise2[k];
      const double* u = signal_var_[entry][k].data();
      for (long long j = j0; j < j1; ++j) {
        const double mm = m[j + shift], r = mm - t[j], w = 1.0 / (n2 + u[j]);
        sa += r * r * w - mm * mm * w_out;
        sb += r * d[j] * w;
        sc += d[j] * d[j] * w;
        sf += r * e2[j] * w;
        sg += d[j] * e2[j] * w;
        sh += e2[j] * e2[j] * w;
      }
    } else {
      const double* inv = inv_signal_var_[entry][k].data();
      for (long long j = j0; j < j1; ++j) {
        const double mm = m[j + shift], r = mm - t[j], w = inv[j];
        sa += r * r * w - mm * mm * w_out;
        sb += r * d[j] * w;
        sc += d[j] * d[j] * w;
        sf += r * e2[j] * w;
        sg += d[j] * e2[j] * w;
        sh += e2[j] * e2[j] * w;
      }
    }
    a += sa;
    bsum += sb;
    c += sc;
    cf += sf;
    cg += sg;
    ch += sh;
  }
  return profile_delta(a, bsum, c, cf, cg, ch, log_det(shot.noise2, entry));
}

RtInversion::ShotTerms RtInversion::shot_terms(const RtPreparedShot& shot) const {
  ShotTerms terms;
  for (const std::vector<double>& m : shot.measured) {
    std::vector<double> m2_m(2 * m.size()), prefix(m.size() + 1, 0.0);
    for (std::size_t b = 0; b < m.size(); ++b) {
      m2_m[2 * b] = m[b] * m[b];
      m2_m[2 * b + 1] = m[b];
      prefix[b + 1] = prefix[b] + m2_m[2 * b];
    }
    terms.m2_m.push_back(std::move(m2_m));
    terms.prefix_m2.push_back(std::move(prefix));
  }
  return terms;
}

void RtInversion::entry_terms(const std::vector<double>& noise2, std::size_t entry,
                              const EntryBand* bands, EntryTerms& terms) const {
  terms.bands.resize(noise2.size());
  for (std::size_t k = 0; k < noise2.size(); ++k) {
    EntryTerms::Band& b = terms.bands[k];
    b.begin = static_cast<long long>(support_begin_[entry][k]);
    b.end = std::max(b.begin, static_cast<long long>(support_end_[entry][k]));
    const std::size_t n = b.n();
    b.t = bands[k].t + b.begin;
    b.slope = bands[k].slope + b.begin;
    b.curvature = bands[k].curvature + b.begin;
    b.data = std::make_unique_for_overwrite<double[]>(4 * n);
    double* x = b.data.get();
    const double n2 = noise2[k];
    const double* u = signal_var_[entry][k].data() + b.begin;
    const double* inv = inv_signal_var_[entry][k].data() + b.begin;
    for (std::size_t i = 0; i < n; ++i) {
      const double w = n2 > 0.0 ? 1.0 / (n2 + u[i]) : inv[i];
      x[4 * i] = w;
      x[4 * i + 1] = b.t[i] * w;
      x[4 * i + 2] = b.slope[i] * w;
      x[4 * i + 3] = b.curvature[i] * w;
    }
    entry_sums(b, 0, n, b.total);
  }
  terms.log_det = log_det(noise2, entry);
}

void RtInversion::entry_sums(const EntryTerms::Band& b, std::size_t i0, std::size_t i1,
                             double sums[6]) {
  const double *t = b.t, *d = b.slope, *e2 = b.curvature, *x = b.data.get();
  // Two lanes a sum (the bins i0 + even and i0 + odd), fixed as fit_terms's are.
  Pair q[6] = {};
  const auto add = [&](std::size_t i, std::size_t lane) {
    const double tw = x[4 * i + 1], dw = x[4 * i + 2], ew = x[4 * i + 3];
    const double products[6] = {t[i] * tw, t[i] * dw, t[i] * ew, d[i] * dw, d[i] * ew, e2[i] * ew};
    for (int r = 0; r < 6; ++r) q[r][lane] += products[r];
  };
  std::size_t i = i0;
  for (; i + 2 <= i1; i += 2) {
    add(i, 0);
    add(i + 1, 1);
  }
  if (i < i1) add(i, 0);
  for (int r = 0; r < 6; ++r) sums[r] = q[r][0] + q[r][1];
}

// fit_calibrated's sums regrouped, r = m - T~ over the bins j of the support within R:
// sum r^2 w - m^2 w_out = sum m^2 w - 2 sum m T~w + sum T~^2 w - w_out sum m^2, and the slope's
// and curvature's alike; what holds m is correlated here, the rest is the entry's own sums.
RtInversion::Fit RtInversion::fit_terms(const RtPreparedShot& shot, const ShotTerms& shot_terms,
                                        const EntryTerms& terms, int shift) const {
  double a = shot.outside, bsum = 0.0, c = 0.0, cf = 0.0, cg = 0.0, ch = 0.0;
  for (std::size_t k = 0; k < terms.bands.size(); ++k) {
    const EntryTerms::Band& b = terms.bands[k];
    const long long j0 =
        std::max<long long>(static_cast<long long>(shot.region_begin) - shift, b.begin);
    const long long j1 =
        std::min<long long>(static_cast<long long>(shot.region_end) - shift, b.end);
    if (j0 >= j1) continue;
    const std::size_t i0 = static_cast<std::size_t>(j0 - b.begin);
    const std::size_t i1 = static_cast<std::size_t>(j1 - b.begin);
    // Per bin: (m^2, m) . (w, T~ w) and (m, m) . (T~' w, T~'' w), in four lanes a sum (lane l
    // the bins i = l mod 4, in order), fixed by the code rather than by the vector width the
    // compiler picks, so that the bits are the same on every x86-64.
    const double* mm = shot_terms.m2_m[k].data() + 2 * (j0 + shift);
    const double* x = b.data.get() + 4 * i0;
    Pair q01[4] = {}, q23[4] = {};
    const std::size_t n = i1 - i0;
    std::size_t i = 0;
    for (; i + 4 <= n; i += 4) {
      for (std::size_t l = 0; l < 4; ++l) {
        const double* at = x + 4 * (i + l);
        const double m = mm[2 * (i + l) + 1];
        q01[l] += load_pair(mm + 2 * (i + l)) * load_pair(at);
        q23[l] += Pair{m, m} * load_pair(at + 2);
      }
    }
    for (; i < n; ++i) {
      const double m = mm[2 * i + 1];
      q01[0] += load_pair(mm + 2 * i) * load_pair(x + 4 * i);
      q23[0] += Pair{m, m} * load_pair(x + 4 * i + 2);
    }
    const Pair s01 = (q01[0] + q01[1]) + (q01[2] + q01[3]);
    const Pair s23 = (q23[0] + q23[1]) + (q23[2] + q23[3]);
    const double sum[4] = {s01[0], s01[1], s23[0], s23[1]};
    double part[6];
    const double* over = b.total;
    if (i0 > 0 || i1 < b.n()) {  // R cuts the support: the waveform's ends
      entry_sums(b, i0, i1, part);
      over = part;
    }
    const std::vector<double>& pm2 = shot_terms.prefix_m2[k];
    a += sum[0] - 2.0 * sum[1] + over[0] - shot.w_out[k] * (pm2[j1 + shift] - pm2[j0 + shift]);
    bsum += sum[2] - over[1];
    c += over[3];
    cf += sum[3] - over[2];
    cg += over[4];
    ch += over[5];
  }
  return profile_delta(a, bsum, c, cf, cg, ch, terms.log_det);
}

// chi2(delta) = A + 2 B delta + (C - F) delta^2 - G delta^3 + H delta^4 / 4 (T~'s second order
// expansion, T'' the bins' second difference): Newton from the first order's minimum.
RtInversion::Fit RtInversion::profile_delta(double a, double bsum, double c, double cf, double cg,
                                            double ch, double log_det) {
  const auto chi2_at = [&](double x) {
    return a + x * (2.0 * bsum + x * ((c - cf) + x * (-cg + 0.25 * x * ch)));
  };
  Fit f;
  double x = c > 0.0 ? std::clamp(-bsum / c, -0.5, 0.5) : 0.0;
  for (int iteration = 0; iteration < 3; ++iteration) {
    const double g1 = 2.0 * bsum + x * (2.0 * (c - cf) + x * (-3.0 * cg + x * ch));
    const double g2 = 2.0 * (c - cf) + x * (-6.0 * cg + 3.0 * x * ch);
    if (!(g2 > 0.0)) break;
    x = std::clamp(x - g1 / g2, -0.5, 0.5);
  }
  f.delta = x;
  f.chi2 = chi2_at(x);
  f.log_det = log_det;
  return f;
}

std::vector<RtInversion::Cell> RtInversion::search(
    const RtPreparedShot& p, std::int64_t excluded,
    const std::vector<const EntryBand*>& override_bands, bool* at_edge,
    const std::vector<EntryTerms>* shared) const {
  const std::size_t entries = table_.entries();
  const double tau = tempering_;
  std::vector<EntryBand> scratch;
  const auto bands_of = [&](std::size_t e) -> const EntryBand* {
    if (!override_bands.empty() && override_bands[e]) return override_bands[e];
    scratch = own_bands(e);
    return scratch.data();
  };
  // Each entry's terms: shared, or built at its first cell and kept for the shifts that follow.
  const ShotTerms shot_sums = shot_terms(p);
  std::vector<const EntryTerms*> terms(entries, nullptr);
  std::vector<std::unique_ptr<EntryTerms>> own(entries);
  const auto cell = [&](std::size_t e, int s) {
    if (!terms[e]) {
      if (shared && (override_bands.empty() || !override_bands[e])) {
        terms[e] = &(*shared)[e];
      } else {
        own[e] = std::make_unique<EntryTerms>();
        entry_terms(p.noise2, e, bands_of(e), *own[e]);
        terms[e] = own[e].get();
      }
    }
    const Fit f = fit_terms(p, shot_sums, *terms[e], s);
    return Cell{static_cast<std::uint32_t>(e), s, -(f.chi2 + f.log_det) / (2.0 * tau), f.chi2,
                f.delta};
  };
  std::vector<Cell> cells;
  *at_edge = false;
  if (settings_.search == RtSearch::direct) {
    for (std::size_t e = 0; e < entries; ++e) {
      if (static_cast<std::int64_t>(e) == excluded) continue;
      for (int s = p.first_shift; s <= p.last_shift; ++s) cells.push_back(cell(e, s));
    }
    const auto best = std::max_element(
        cells.begin(), cells.end(),
        [](const Cell& x, const Cell& y) { return x.log_likelihood < y.log_likelihood; });
    *at_edge = best != cells.end() && (best->shift == p.first_shift || best->shift == p.last_shift);
    return cells;
  }
  // Stage 1: the ground. The design's first entries, every other bin over the wide window, by
  // least squares on band 0 (sum over the entry's support of T^2 - 2 m T).
  const std::vector<double>& m = p.measured[0];
  const long long n = static_cast<long long>(m.size());
  double best_score = std::numeric_limits<double>::infinity();
  int ground = p.centre_shift;
  const std::size_t coarse = std::min<std::size_t>(16, entries);
  const auto score = [&](std::size_t e, int s) {
    const double* t = emulated_[e][0].data();
    const long long j0 = std::max<long long>(-s, static_cast<long long>(support_begin_[e][0]));
    const long long j1 = std::min<long long>(n - s, static_cast<long long>(support_end_[e][0]));
    double sum = 0.0;
    for (long long j = j0; j < j1; ++j) sum += t[j] * (t[j] - 2.0 * m[j + s]);
    return sum;
  };
  const auto scan = [&](int from, int to, int step) {
    for (int s = from; s <= to; s += step) {
      for (std::size_t e = 0; e < coarse; ++e) {
        if (static_cast<std::int64_t>(e) == excluded) continue;
        const double v = score(e, s);
        if (v < best_score) {
          best_score = v;
          ground = s;
        }
      }
    }
  };
  scan(p.first_shift, p.last_shift, 2);
  const int coarse_ground = ground;
  scan(std::max(p.first_shift, coarse_ground - 1), std::min(p.last_shift, coarse_ground + 1), 1);
  // Stage 2: every entry at that ground (projected: those the components cannot rule out);
  // those within prune_log_likelihood of the best kept.
  bool projected =
      settings_.search == RtSearch::projected && override_bands.empty() &&
      entries >= static_cast<std::size_t>(std::max(0, settings_.projection_min_entries));
  std::vector<std::size_t> candidates;
  if (projected) candidates = prefilter(p, ground, excluded, &projected);
  // A dense table's region of the posterior: the design's first max_exact_entries of it (a
  // Halton design's prefix is itself a design of the same region, as a coarser table).
  const std::size_t most = static_cast<std::size_t>(std::max(0, settings_.max_exact_entries));
  if (projected && most > 0 && candidates.size() > most) candidates.resize(most);
  if (!projected) {
    candidates.clear();
    for (std::size_t e = 0; e < entries; ++e)
      if (static_cast<std::int64_t>(e) != excluded) candidates.push_back(e);
  }
  std::vector<Cell> first;
  first.reserve(candidates.size());
  double best = -std::numeric_limits<double>::infinity();
  for (std::size_t e : candidates) {
    first.push_back(cell(e, ground));
    best = std::max(best, first.back().log_likelihood);
  }
  std::vector<std::size_t> kept;
  for (const Cell& c : first)
    if (c.log_likelihood >= best - settings_.prune_log_likelihood) kept.push_back(c.entry);
  // Stage 3: the kept entries over the shifts about it, widened while an edge holds mass.
  cells = std::move(first);
  cells.erase(std::remove_if(cells.begin(), cells.end(),
                             [&](const Cell& c) {
                               return c.log_likelihood < best - settings_.prune_log_likelihood;
                             }),
              cells.end());
  // Outward from that ground, one shift at a time each way, each entry while it stayed within
  // prune_log_likelihood of the best at the shift before (a flood fill of the likely cells).
  for (const int step : {-1, 1}) {
    std::vector<std::size_t> active = kept;
    for (int s = ground + step; s >= p.first_shift && s <= p.last_shift && !active.empty();
         s += step) {
      std::vector<std::size_t> next;
      for (std::size_t e : active) {
        cells.push_back(cell(e, s));
        best = std::max(best, cells.back().log_likelihood);
        if (cells.back().log_likelihood >= best - settings_.prune_log_likelihood) next.push_back(e);
      }
      active = std::move(next);
    }
  }
  const auto top = std::max_element(cells.begin(), cells.end(), [](const Cell& x, const Cell& y) {
    return x.log_likelihood < y.log_likelihood;
  });
  *at_edge = top != cells.end() && (top->shift <= p.first_shift || top->shift >= p.last_shift);
  return cells;
}

void RtInversion::entry_statistics(const std::vector<double>& entry_weight, RtResult& r) const {
  RtStatistic* statistics[] = {&r.canopy_height_m, &r.cover, &r.pai, &r.rhov_rhog, &r.pgap};
  for (std::size_t v = 0; v < truths_.size(); ++v)
    *statistics[v] = weighted_statistic(*truths_[v], entry_weight, sorted_[v]);
}

RtResult RtInversion::summarise(const RtPreparedShot& p, const std::vector<Cell>& cells,
                                bool at_edge) const {
  const std::size_t entries = table_.entries();
  if (cells.empty()) return RtResult::none();
  const Cell* top = &cells[0];
  for (const Cell& c : cells)
    if (c.log_likelihood > top->log_likelihood) top = &c;
  std::vector<double> entry_weight(entries, 0.0);
  const int shifts = p.last_shift - p.first_shift + 1;
  std::vector<double> shift_weight(shifts, 0.0), shift_delta(shifts, 0.0);
  for (const Cell& c : cells) {
    const double w = std::exp(c.log_likelihood - top->log_likelihood);
    entry_weight[c.entry] += w;
    shift_weight[c.shift - p.first_shift] += w;
    shift_delta[c.shift - p.first_shift] += w * c.delta;
  }
  RtResult r;
  entry_statistics(entry_weight, r);
  std::vector<double> grounds(shifts);
  std::vector<std::uint32_t> order(shifts);
  for (int s = 0; s < shifts; ++s) {
    const double delta = shift_weight[s] > 0.0 ? shift_delta[s] / shift_weight[s] : 0.0;
    grounds[s] = ground_elevation_m(p, p.first_shift + s) + delta * p.dz_m;
    order[s] = static_cast<std::uint32_t>(shifts - 1 - s);  // dz < 0: the last shift is lowest
  }
  r.ground_elevation_m = weighted_statistic(grounds, shift_weight, order);
  r.chi2_min = top->chi2;
  r.best_entry = top->entry;
  r.best_ground_elevation_m = ground_elevation_m(p, top->shift) + top->delta * p.dz_m;
  r.ground_guess_m = p.ground_guess_m;
  // Degrees of freedom: the bins of R where the shot or the best fit stands above the floor.
  std::size_t signal = 0;
  for (std::size_t k = 0; k < p.measured.size(); ++k) {
    const std::vector<double>& t = emulated_[top->entry][k];
    const long long bins = static_cast<long long>(t.size());
    for (std::size_t b = p.region_begin; b < p.region_end; ++b) {
      const long long j = static_cast<long long>(b) - top->shift;
      const double tj = j >= 0 && j < bins ? t[j] : 0.0;
      signal += std::max(std::abs(p.measured[k][b]), tj) > signal_floor_W_[k];
    }
  }
  r.dof = static_cast<double>(std::max<std::size_t>(1, signal));
  if (r.chi2_min / r.dof > settings_.chi2_dof_limit) r.flag |= rt_misfit;
  if (posterior_at_table_edge(entry_weight)) r.flag |= rt_table_edge;
  if (at_edge) r.flag |= rt_ground_search_edge;
  if (std::abs(r.ground_elevation_m.mean - p.ground_guess_m) > settings_.ground_offset_flag_m)
    r.flag |= rt_ground_off_guess;
  return r;
}

RtResult RtInversion::invert(const RtShot& shot) const {
  if (settings_.likelihood == RtLikelihood::calibrated) {
    const int half =
        settings_.search == RtSearch::direct
            ? (settings_.search_half_width_bins > 0
                   ? settings_.search_half_width_bins
                   : std::max(4, static_cast<int>(
                                     std::ceil(1.5 * table_.pulse_sigma_ns / table_.bin_ns))))
            : std::max(4, static_cast<int>(std::ceil(settings_.ground_search_m /
                                                     (0.5 * 0.299792458 * table_.bin_ns))));
    const RtPreparedShot p = prepare_window(shot, std::numeric_limits<int>::min(), half);
    if (!p.usable) return RtResult::none();
    bool at_edge = false;
    const std::vector<Cell> cells = search(p, -1, {}, &at_edge);
    return summarise(p, cells, at_edge);
  }
  const RtPreparedShot p = prepare(shot);
  if (!p.usable) return RtResult::none();
  const std::size_t entries = table_.entries();
  const int shifts = p.last_shift - p.first_shift + 1;
  std::vector<double> chi2(entries * shifts);
  double best = std::numeric_limits<double>::infinity();
  std::size_t best_index = 0;
  for (std::size_t e = 0; e < entries; ++e) {
    for (int s = 0; s < shifts; ++s) {
      const double c = fit(p, e, p.first_shift + s).chi2;
      chi2[e * shifts + s] = c;
      if (c < best) {
        best = c;
        best_index = e * shifts + s;
      }
    }
  }
  std::vector<double> entry_weight(entries, 0.0), shift_weight(shifts, 0.0);
  for (std::size_t e = 0; e < entries; ++e) {
    for (int s = 0; s < shifts; ++s) {
      const double w = std::exp(-0.5 * (chi2[e * shifts + s] - best));
      entry_weight[e] += w;
      shift_weight[s] += w;
    }
  }
  RtResult r;
  entry_statistics(entry_weight, r);
  std::vector<double> grounds(shifts);
  std::vector<std::uint32_t> order(shifts);
  for (int s = 0; s < shifts; ++s) {
    grounds[s] = ground_elevation_m(p, p.first_shift + s);
    order[s] = static_cast<std::uint32_t>(shifts - 1 - s);  // dz < 0: the last shift is lowest
  }
  r.ground_elevation_m = weighted_statistic(grounds, shift_weight, order);
  r.chi2_min = best;
  r.ground_guess_m = p.ground_guess_m;
  r.dof = static_cast<double>((p.region_end - p.region_begin) * p.measured.size());
  r.best_entry = static_cast<std::int64_t>(best_index / shifts);
  if (best / std::max(1.0, r.dof) > settings_.chi2_dof_limit) r.flag |= rt_misfit;
  if (posterior_at_table_edge(entry_weight)) r.flag |= rt_table_edge;
  const int best_shift = static_cast<int>(best_index % shifts);
  r.best_ground_elevation_m = ground_elevation_m(p, p.first_shift + best_shift);
  if (best_shift == 0 || best_shift == shifts - 1) r.flag |= rt_ground_search_edge;
  return r;
}

bool RtInversion::posterior_at_table_edge(const std::vector<double>& entry_weight) const {
  const double total = std::accumulate(entry_weight.begin(), entry_weight.end(), 0.0);
  for (std::size_t q = 0; q < table_.parameters.size(); ++q) {
    double low = 0.0, high = 0.0;
    for (std::size_t e = 0; e < entry_weight.size(); ++e) {
      if (edge_[e][q] == 1) low += entry_weight[e];
      if (edge_[e][q] == 2) high += entry_weight[e];
    }
    if (low > settings_.edge_mass * total || high > settings_.edge_mass * total) return true;
  }
  return false;
}

}  // namespace glaswave
