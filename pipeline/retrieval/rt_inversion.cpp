// The rt inversion: the likelihood of a measured waveform under each table entry, the posterior
// over the entries and the ground, and its statistics and flags (rt_inversion.hpp says how).
#include "pipeline/retrieval/rt_inversion.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "core/error.hpp"

namespace glaswave {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

RtStatistic no_statistic() { return {kNaN, kNaN, kNaN, kNaN}; }

// Mean, sd and the 5 % and 95 % points of values weighted by w, the values visited in increasing
// order (`order`); entries whose value is NaN are left out. A quantile is the first value at
// which the cumulative weight reaches it.
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
    if (!std::isnan(values[i]) && w[i] > 0.0) sum2 += w[i] * (values[i] - mean) * (values[i] - mean);
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

}  // namespace

RtResult RtResult::none() {
  RtResult r;
  r.canopy_height_m = r.cover = r.pai = r.ground_elevation_m = r.rhov_rhog = no_statistic();
  r.chi2_min = r.dof = kNaN;
  r.flag = rt_not_run;
  return r;
}

RtInversion::RtInversion(const ForwardTable& table, const RtSettings& settings)
    : table_(table), settings_(settings) {
  mc_relative_sd_ = settings.mc_relative_sd >= 0.0 ? settings.mc_relative_sd
                    : std::isfinite(table.mc_relative_sd) ? table.mc_relative_sd
                                                           : settings.mc_relative_sd_fallback;
  const std::size_t entries = table.entries(), bands = table.bands(), bins = table.height_m.size();
  support_begin_.assign(entries, std::vector<std::size_t>(bands, 0));
  support_end_.assign(entries, std::vector<std::size_t>(bands, 0));
  prefix_tt_.assign(entries, std::vector<std::vector<double>>(bands));
  for (std::size_t e = 0; e < entries; ++e) {
    for (std::size_t k = 0; k < bands; ++k) {
      const std::vector<double>& t = table.waveform_W[e][k];
      const double peak = *std::max_element(t.begin(), t.end());
      std::size_t begin = bins, end = 0;
      for (std::size_t j = 0; j < bins; ++j) {
        if (t[j] > 1e-4 * peak) {
          begin = std::min(begin, j);
          end = j + 1;
        }
      }
      if (begin > end) begin = end = 0;
      support_begin_[e][k] = begin;
      support_end_[e][k] = end;
      std::vector<double>& prefix = prefix_tt_[e][k];
      prefix.assign(bins + 1, 0.0);
      for (std::size_t j = 0; j < bins; ++j) prefix[j + 1] = prefix[j] + t[j] * t[j];
    }
  }
  const std::vector<const std::vector<double>*> variables = {
      &table.canopy_height_true_m, &table.cover_true, &table.pai_true, &table.rhov_rhog};
  for (const std::vector<double>* v : variables) {
    std::vector<std::uint32_t> order(entries);
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
      return (*v)[a] < (*v)[b] || (std::isnan((*v)[b]) && !std::isnan((*v)[a]));
    });
    sorted_.push_back(std::move(order));
  }
  edge_.assign(entries, std::vector<std::uint8_t>(table.parameters.size(), 0));
  for (std::size_t p = 0; p < table.parameters.size(); ++p) {
    const TableParameter& parameter = table.parameters[p];
    if (!parameter.is_range() || !(parameter.high > parameter.low)) continue;
    for (std::size_t e = 0; e < entries; ++e) {
      const double u =
          (table.parameter_values[e][p] - parameter.low) / (parameter.high - parameter.low);
      edge_[e][p] = u < settings.edge_fraction ? 1 : u > 1.0 - settings.edge_fraction ? 2 : 0;
    }
  }
}

void RtInversion::check_compatible(const std::vector<std::string>& band_names, double bin_ns,
                                   const std::string& table_place) const {
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
}

RtPreparedShot RtInversion::prepare(const RtShot& shot) const {
  RtPreparedShot p;
  const std::size_t bands = table_.bands();
  if (shot.waveform.size() != bands || shot.waveform.empty()) return p;
  const std::size_t n = shot.waveform[0].size();
  if (n < 2) return p;
  p.z0_m = shot.axis.elev_bin0_m;
  p.dz_m = (shot.axis.elev_lastbin_m - shot.axis.elev_bin0_m) / static_cast<double>(n - 1);
  if (!std::isfinite(p.dz_m) || p.dz_m >= 0.0) return p;
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
    p.sigma.push_back(std::sqrt(noise * noise + f2 * peak * peak));
    if (!(p.sigma.back() > 0.0)) return p;
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
  const double h0 = table_.height_m.front();
  const int centre = static_cast<int>(std::lround((guess + h0 - p.z0_m) / p.dz_m));
  const int half = settings_.search_half_width_bins > 0
                       ? settings_.search_half_width_bins
                       : std::max(4, static_cast<int>(std::ceil(1.5 * sigma_bins)));
  p.first_shift = centre - half;
  p.last_shift = centre + half;
  const long long bins = static_cast<long long>(table_.height_m.size());
  const long long begin = std::max<long long>(0, p.first_shift);
  const long long end = std::min<long long>(static_cast<long long>(n), p.last_shift + bins);
  if (begin >= end) return p;
  p.region_begin = static_cast<std::size_t>(begin);
  p.region_end = static_cast<std::size_t>(end);
  for (const std::vector<double>& m : p.measured) {
    double m2 = 0.0;
    for (std::size_t b = p.region_begin; b < p.region_end; ++b) m2 += m[b] * m[b];
    p.m2.push_back(m2);
  }
  p.usable = true;
  return p;
}

double RtInversion::ground_elevation_m(const RtPreparedShot& shot, int shift) const {
  return shot.z0_m + shift * shot.dz_m - table_.height_m.front();
}

RtInversion::Fit RtInversion::fit(const RtPreparedShot& shot, std::size_t entry, int shift) const {
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
    const long long a1 = std::min<long long>({bins, static_cast<long long>(shot.region_end) - shift, n - shift});
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

RtResult RtInversion::invert(const RtShot& shot) const {
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
  r.canopy_height_m = weighted_statistic(table_.canopy_height_true_m, entry_weight, sorted_[0]);
  r.cover = weighted_statistic(table_.cover_true, entry_weight, sorted_[1]);
  r.pai = weighted_statistic(table_.pai_true, entry_weight, sorted_[2]);
  r.rhov_rhog = weighted_statistic(table_.rhov_rhog, entry_weight, sorted_[3]);
  std::vector<double> grounds(shifts);
  std::vector<std::uint32_t> order(shifts);
  for (int s = 0; s < shifts; ++s) {
    grounds[s] = ground_elevation_m(p, p.first_shift + s);
    order[s] = static_cast<std::uint32_t>(shifts - 1 - s);  // dz < 0: the last shift is lowest
  }
  r.ground_elevation_m = weighted_statistic(grounds, shift_weight, order);
  r.chi2_min = best;
  r.dof = static_cast<double>((p.region_end - p.region_begin) * p.measured.size());
  r.best_entry = static_cast<std::int64_t>(best_index / shifts);
  if (best / std::max(1.0, r.dof) > settings_.chi2_dof_limit) r.flag |= rt_misfit;
  const double total = std::accumulate(entry_weight.begin(), entry_weight.end(), 0.0);
  for (std::size_t q = 0; q < table_.parameters.size(); ++q) {
    double low = 0.0, high = 0.0;
    for (std::size_t e = 0; e < entries; ++e) {
      if (edge_[e][q] == 1) low += entry_weight[e];
      if (edge_[e][q] == 2) high += entry_weight[e];
    }
    if (low > settings_.edge_mass * total || high > settings_.edge_mass * total)
      r.flag |= rt_table_edge;
  }
  const int best_shift = static_cast<int>(best_index % shifts);
  if (best_shift == 0 || best_shift == shifts - 1) r.flag |= rt_ground_search_edge;
  return r;
}

}  // namespace glaswave
