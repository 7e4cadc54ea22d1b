// The rt inversion: the likelihood of a measured waveform under each table entry, the posterior
// over the entries and the ground, and its statistics and flags (rt_inversion.hpp says how).
#include "pipeline/retrieval/rt_inversion.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>

#include "core/error.hpp"

namespace glaswave {

namespace {

// The bins [begin, end) from the first to the last of `values` above `level`; [0, 0) for none.
std::pair<std::size_t, std::size_t> support_above(const std::vector<double>& values, double level) {
  std::size_t begin = values.size(), end = 0;
  for (std::size_t j = 0; j < values.size(); ++j) {
    if (values[j] > level) {
      begin = std::min(begin, j);
      end = j + 1;
    }
  }
  if (begin > end) begin = end = 0;
  return {begin, end};
}

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// The grid of detector noise variances on which sum log V is tabulated: u_out 2^(g - 24).
constexpr int kLogDetGrid = 40, kLogDetGridLow = -24;
// The 90th percentile of a chi-squared variable of one degree of freedom: a Gaussian z's 90 %
// interval is |z| < 1.645.
constexpr double kP90Chi2One = 2.705543;

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

}  // namespace

RtResult RtResult::none() {
  RtResult r;
  r.canopy_height_m = r.cover = r.pai = r.ground_elevation_m = r.rhov_rhog = no_statistic();
  r.chi2_min = r.dof = r.ground_guess_m = r.best_ground_elevation_m = kNaN;
  r.flag = rt_not_run;
  return r;
}

RtInversion::RtInversion(const ForwardTable& table, const RtSettings& settings)
    : table_(table), settings_(settings) {
  mc_relative_sd_ = settings.mc_relative_sd >= 0.0        ? settings.mc_relative_sd
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
      const auto [begin, end] = support_above(t, 1e-4 * peak);
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
  if (settings_.likelihood != RtLikelihood::calibrated) return;
  const double rays = settings.measured_rays_per_shot > 0.0
                          ? settings.measured_rays_per_shot
                          : static_cast<double>(table.rays_per_shot);
  measured_factor_ = !settings.measured_is_simulated ? 0.0
                     : rays > 0.0 && table.rays_per_shot > 0
                         ? static_cast<double>(table.rays_per_shot) / rays
                         : 1.0;
  build_emulator();
  fit_noise_model();
  build_variances();
  tempering_ = settings.tempering > 0.0 ? settings.tempering : 1.0;
  if (settings.tempering <= 0.0 && table.shot0_W.size() == entries && entries > 2)
    calibrate_tempering();
}

// The local linear emulator: at entry e, the intercept of the least-squares plane through its k
// nearest entries (normalised coordinates of the ranges; listed keys must be equal), as weights
// on their waveforms. Its variance over one entry's: sum of the squared weights.
void RtInversion::build_emulator() {
  const ForwardTable& t = table_;
  const std::size_t entries = t.entries(), bands = t.bands(), bins = t.height_m.size();
  std::vector<std::size_t> ranges, lists;
  for (std::size_t p = 0; p < t.parameters.size(); ++p) {
    if (t.parameters[p].is_range() && t.parameters[p].high > t.parameters[p].low)
      ranges.push_back(p);
    else if (!t.parameters[p].is_range())
      lists.push_back(p);
  }
  const std::size_t d = ranges.size();
  std::size_t k = settings_.emulator_neighbours > 0 ? settings_.emulator_neighbours
                                                    : std::max<std::size_t>(16, 4 * (d + 1));
  k = std::min(k, entries);
  const auto coordinate = [&](std::size_t e, std::size_t i) {
    const TableParameter& p = t.parameters[ranges[i]];
    return (t.parameter_values[e][ranges[i]] - p.low) / (p.high - p.low);
  };
  smoother_.assign(entries, {});
  leverage_.assign(entries, 1.0);
  std::vector<std::pair<double, std::uint32_t>> near;
  for (std::size_t e = 0; e < entries; ++e) {
    near.clear();
    for (std::size_t f = 0; f < entries; ++f) {
      bool same = true;
      for (std::size_t p : lists)
        same = same && t.parameter_values[f][p] == t.parameter_values[e][p];
      if (!same) continue;
      double d2 = 0.0;
      for (std::size_t i = 0; i < d; ++i) d2 += std::pow(coordinate(f, i) - coordinate(e, i), 2);
      near.push_back({d2, static_cast<std::uint32_t>(f)});
    }
    const std::size_t n = std::min(k, near.size());
    std::partial_sort(near.begin(), near.begin() + n, near.end());
    std::vector<std::pair<std::uint32_t, double>>& weights = smoother_[e];
    if (n <= d + 1 || k == 1) {
      weights = {{static_cast<std::uint32_t>(e), 1.0}};
    } else {
      Eigen::MatrixXd x(n, d + 1);
      for (std::size_t r = 0; r < n; ++r) {
        x(r, 0) = 1.0;
        for (std::size_t i = 0; i < d; ++i)
          x(r, i + 1) = coordinate(near[r].second, i) - coordinate(e, i);
      }
      const Eigen::MatrixXd normal = x.transpose() * x;
      Eigen::VectorXd unit = Eigen::VectorXd::Zero(d + 1);
      unit(0) = 1.0;
      const auto solver = normal.ldlt();
      const Eigen::VectorXd beta = solver.solve(unit);
      const Eigen::VectorXd hat = x * beta;  // the intercept's weights on the neighbours
      if (solver.info() != Eigen::Success || !hat.allFinite() || std::abs(hat.sum() - 1.0) > 1e-6) {
        for (std::size_t r = 0; r < n; ++r) weights.push_back({near[r].second, 1.0 / n});
      } else {
        for (std::size_t r = 0; r < n; ++r) weights.push_back({near[r].second, hat(r)});
      }
    }
    double h = 0.0;
    for (const auto& [f, w] : weights) h += w * w;
    leverage_[e] = h;
  }
  emulated_.assign(entries,
                   std::vector<std::vector<double>>(bands, std::vector<double>(bins, 0.0)));
  slope_ = emulated_;
  curvature_ = emulated_;
  for (std::size_t e = 0; e < entries; ++e) {
    for (std::size_t b = 0; b < bands; ++b) {
      std::vector<double>& out = emulated_[e][b];
      for (const auto& [f, w] : smoother_[e])
        for (std::size_t j = 0; j < bins; ++j) out[j] += w * t.waveform_W[f][b][j];
      for (double& x : out) x = std::max(0.0, x);
      for (std::size_t j = 1; j + 1 < bins; ++j) {
        slope_[e][b][j] = 0.5 * (out[j + 1] - out[j - 1]);
        curvature_[e][b][j] = out[j + 1] - 2.0 * out[j] + out[j - 1];
      }
    }
  }
}

// v(T) = a T + c T^2 per band, from each entry's first shot about its mean: Var(shot - mean) =
// v (1 - 1/K). Iteratively reweighted least squares of the squared residuals (their variance
// 2 v^2) on T and T^2, over the bins above 1e-3 of the entry's peak; a coefficient that comes out
// negative is dropped. Without first shots: a = f^2 times the median peak (the first cut's f at
// the peak, Poisson-like below it).
void RtInversion::fit_noise_model() {
  const ForwardTable& t = table_;
  const std::size_t entries = t.entries(), bands = t.bands(), bins = t.height_m.size();
  var_linear_.assign(bands, 0.0);
  var_quadratic_.assign(bands, 0.0);
  signal_floor_W_.assign(bands, 0.0);
  for (std::size_t b = 0; b < bands; ++b) {
    std::vector<double> peaks;
    for (std::size_t e = 0; e < entries; ++e)
      peaks.push_back(*std::max_element(t.waveform_W[e][b].begin(), t.waveform_W[e][b].end()));
    std::vector<double> sorted = peaks;
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    const double median_peak = sorted[sorted.size() / 2];
    const double max_peak = *std::max_element(peaks.begin(), peaks.end());
    double a = mc_relative_sd_ * mc_relative_sd_ * median_peak, c = 0.0;
    if (t.shot0_W.size() == entries && t.shots_per_entry >= 2) {
      const double keep = 1.0 - 1.0 / static_cast<double>(t.shots_per_entry);
      std::vector<double> xs, ys;
      for (std::size_t e = 0; e < entries; ++e) {
        for (std::size_t j = 0; j < bins; ++j) {
          const double mean = t.waveform_W[e][b][j];
          if (!(mean > 1e-3 * peaks[e])) continue;
          const double r = t.shot0_W[e][b][j] - mean;
          xs.push_back(mean);
          ys.push_back(r * r / keep);
        }
      }
      bool use_a = true, use_c = true;
      for (int round = 0; round < 2 && xs.size() >= 2; ++round) {
        double fa = 0.0, fc = 0.0;
        for (int iteration = 0; iteration < 4; ++iteration) {
          double saa = 0, sac = 0, scc = 0, say = 0, scy = 0;
          for (std::size_t i = 0; i < xs.size(); ++i) {
            const double model = iteration == 0 ? xs[i] : fa * xs[i] + fc * xs[i] * xs[i];
            const double w = 1.0 / std::max(model * model, 1e-300);
            const double ua = use_a ? xs[i] : 0.0, uc = use_c ? xs[i] * xs[i] : 0.0;
            saa += w * ua * ua;
            sac += w * ua * uc;
            scc += w * uc * uc;
            say += w * ua * ys[i];
            scy += w * uc * ys[i];
          }
          const double det = saa * scc - sac * sac;
          if (use_a && use_c && det > 0.0) {
            fa = (say * scc - scy * sac) / det;
            fc = (scy * saa - say * sac) / det;
          } else if (use_a && saa > 0.0) {
            fa = say / saa;
            fc = 0.0;
          } else if (use_c && scc > 0.0) {
            fa = 0.0;
            fc = scy / scc;
          }
          if (!(fa > 0.0 || fc > 0.0)) break;
          if (fa < 0.0) fa = 0.0;
          if (fc < 0.0) fc = 0.0;
        }
        a = fa;
        c = fc;
        if (a > 0.0 && c > 0.0) break;
        use_a = a > 0.0;
        use_c = c > 0.0;
        if (!use_a && !use_c) break;
      }
    }
    var_linear_[b] = a;
    var_quadratic_[b] = c;
    // One ray's amplitude (Poisson's a T = a^2 at T = a); never below 1e-6 of the largest peak.
    signal_floor_W_[b] = std::max(a, 1e-6 * max_peak);
  }
}

// u = (r_m + h_e / K) v(max(T~, floor)) per bin, its inverse, and sum log(1 + (u - u_out) /
// (n^2 + u_out)) over the support on a grid of n^2.
void RtInversion::build_variances() {
  const ForwardTable& t = table_;
  const std::size_t entries = t.entries(), bands = t.bands(), bins = t.height_m.size();
  const double per_entry = 1.0 / std::max<double>(1.0, static_cast<double>(t.shots_per_entry));
  out_var_.assign(bands, 0.0);
  for (std::size_t b = 0; b < bands; ++b) {
    const double floor = signal_floor_W_[b];
    const double v = var_linear_[b] * floor + var_quadratic_[b] * floor * floor;
    out_var_[b] = std::max((measured_factor_ + per_entry) * v, 1e-300);
  }
  signal_var_.assign(entries, std::vector<std::vector<double>>(bands));
  inv_signal_var_ = signal_var_;
  log_det_grid_.assign(entries, std::vector<std::vector<double>>(bands));
  for (std::size_t e = 0; e < entries; ++e) {
    const double rho = measured_factor_ + leverage_[e] * per_entry;
    for (std::size_t b = 0; b < bands; ++b) {
      const std::vector<double>& tt = emulated_[e][b];
      const double floor = signal_floor_W_[b];
      const auto [begin, end] = support_above(tt, floor);
      support_begin_[e][b] = begin;
      support_end_[e][b] = end;
      std::vector<double>& u = signal_var_[e][b];
      u.assign(bins, out_var_[b]);
      for (std::size_t j = begin; j < end; ++j) {
        const double s = std::max(tt[j], floor);
        u[j] = std::max(rho * (var_linear_[b] * s + var_quadratic_[b] * s * s), 1e-300);
      }
      inv_signal_var_[e][b].resize(bins);
      for (std::size_t j = 0; j < bins; ++j) inv_signal_var_[e][b][j] = 1.0 / u[j];
      std::vector<double>& grid = log_det_grid_[e][b];
      grid.assign(kLogDetGrid + 1, 0.0);  // [0]: no detector noise; [g + 1]: u_out 2^(g + low)
      for (int g = -1; g < kLogDetGrid; ++g) {
        const double n2 = g < 0 ? 0.0 : out_var_[b] * std::exp2(g + kLogDetGridLow);
        double sum = 0.0;
        for (std::size_t j = begin; j < end; ++j) sum += std::log((n2 + u[j]) / (n2 + out_var_[b]));
        grid[g + 1] = sum;
      }
    }
  }
}

double RtInversion::log_det(const RtPreparedShot& shot, std::size_t entry) const {
  double sum = 0.0;
  for (std::size_t b = 0; b < shot.noise2.size(); ++b) {
    const std::vector<double>& grid = log_det_grid_[entry][b];
    const double n2 = shot.noise2[b];
    if (!(n2 > 0.0)) {
      sum += grid[0];
      continue;
    }
    const double x = std::log2(n2 / out_var_[b]) - kLogDetGridLow;
    if (x <= 0.0) {
      sum += grid[1];
    } else if (x >= kLogDetGrid - 1) {
      sum += grid[kLogDetGrid];
    } else {
      const int g = static_cast<int>(x);
      const double f = x - g;
      sum += (1.0 - f) * grid[g + 1] + f * grid[g + 2];
    }
  }
  return sum;
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
    std::vector<EntryBand> bands;
    for (std::size_t k = 0; k < table_.bands(); ++k)
      bands.push_back(
          {emulated_[entry][k].data(), slope_[entry][k].data(), curvature_[entry][k].data()});
    return fit_calibrated(shot, entry, shift, bands.data());
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

// Over R: chi2 = sum m^2 w_out + sum over the entry's support of [(m - T)^2 w - m^2 w_out],
// w = 1 / (n^2 + u); with T(j - delta) = T - delta T', chi2(delta) = A + 2 delta B + delta^2 C,
// minimised over delta in [-1/2, 1/2].
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
  // chi2(delta) = A + 2 B delta + (C - F) delta^2 - G delta^3 + H delta^4 / 4 (T~'s second order
  // expansion, T'' the bins' second difference): Newton from the first order's minimum.
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
  f.log_det = log_det(shot, entry);
  return f;
}

std::vector<RtInversion::Cell> RtInversion::search(
    const RtPreparedShot& p, std::int64_t excluded,
    const std::vector<const EntryBand*>& override_bands, bool* at_edge) const {
  const std::size_t entries = table_.entries(), bands = table_.bands();
  const double tau = tempering_;
  std::vector<EntryBand> scratch(bands);
  const auto bands_of = [&](std::size_t e) -> const EntryBand* {
    if (!override_bands.empty() && override_bands[e]) return override_bands[e];
    for (std::size_t k = 0; k < bands; ++k)
      scratch[k] = {emulated_[e][k].data(), slope_[e][k].data(), curvature_[e][k].data()};
    return scratch.data();
  };
  const auto cell = [&](std::size_t e, int s) {
    const Fit f = fit_calibrated(p, e, s, bands_of(e));
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

double RtInversion::Projection::transform(std::size_t k, double x) const {
  const std::vector<double>& gk = g[k];
  const double low = floor[k], high = top[k];
  if (x <= low) return gk.front() + (x - low) * slope_low[k];
  const std::size_t steps = gk.size() - 1;
  if (x >= high) return gk.back() + (x - high) * slope_high[k];
  const double span = high - low;
  const double u = std::sqrt((x - low) / span) * static_cast<double>(steps);
  const std::size_t i = std::min(static_cast<std::size_t>(u), steps - 1);
  const double fi = static_cast<double>(i) / steps, fj = static_cast<double>(i + 1) / steps;
  const double xi = low + span * fi * fi, xj = low + span * fj * fj;
  return gk[i] + (gk[i + 1] - gk[i]) * (x - xi) / (xj - xi);
}

// The level of detector noise a shot's projection is built for: each band's noise variance
// rounded to a quarter octave of the table's variance without signal (none below 2^-10 of it).
const RtInversion::Projection& RtInversion::projection(const RtPreparedShot& shot) const {
  std::vector<int> key(shot.noise2.size());
  std::vector<double> level(shot.noise2.size(), 0.0);
  for (std::size_t k = 0; k < key.size(); ++k) {
    const double x = shot.noise2[k] > 0.0 ? 4.0 * std::log2(shot.noise2[k] / out_var_[k]) : -1e9;
    key[k] = x < -40.0 ? std::numeric_limits<int>::min() : static_cast<int>(std::lround(x));
    if (x >= -40.0) level[k] = out_var_[k] * std::exp2(0.25 * key[k]);
  }
  const std::lock_guard<std::mutex> lock(projections_mutex_);
  std::unique_ptr<const Projection>& slot = projections_[key];
  if (!slot) slot = build_projection(level);
  return *slot;
}

// g per band (V(x) = n^2 + rho v(max(x, floor)), rho the median entry's), the transformed
// entries y_e and their slopes y'_e (central differences, as the exact fit's), and the leading
// eigenvectors of sum (y_e - mean)(y_e - mean)^T + y'_e y'_e^T over up to 1500 entries.
std::unique_ptr<RtInversion::Projection> RtInversion::build_projection(
    const std::vector<double>& noise2) const {
  const ForwardTable& t = table_;
  const std::size_t entries = t.entries(), bands = t.bands(), bins = t.height_m.size();
  const double per_entry = 1.0 / std::max<double>(1.0, static_cast<double>(t.shots_per_entry));
  std::vector<double> leverage = leverage_;
  std::nth_element(leverage.begin(), leverage.begin() + leverage.size() / 2, leverage.end());
  const double rho_ref = measured_factor_ + leverage[leverage.size() / 2] * per_entry;
  auto out = std::make_unique<Projection>();
  Projection& q = *out;
  constexpr std::size_t kSteps = 2048;
  for (std::size_t k = 0; k < bands; ++k) {
    const double n2 = noise2[k], a = var_linear_[k], c = var_quadratic_[k];
    const double low = signal_floor_W_[k];
    double peak = 0.0;
    for (std::size_t e = 0; e < entries; ++e)
      peak = std::max(peak, *std::max_element(emulated_[e][k].begin(), emulated_[e][k].end()));
    const double high = std::max(2.0 * peak, 2.0 * low + 1e-300);
    const auto inv_sd = [&](double x) {
      const double s = std::max(x, low);
      return 1.0 / std::sqrt(std::max(n2 + rho_ref * (a * s + c * s * s), 1e-300));
    };
    std::vector<double> g(kSteps + 1);
    g[0] = low * inv_sd(low);
    double x0 = low;
    for (std::size_t i = 1; i <= kSteps; ++i) {  // Simpson's rule on each step
      const double f = static_cast<double>(i) / kSteps, x1 = low + (high - low) * f * f;
      g[i] = g[i - 1] + (x1 - x0) * (inv_sd(x0) + 4.0 * inv_sd(0.5 * (x0 + x1)) + inv_sd(x1)) / 6.0;
      x0 = x1;
    }
    q.g.push_back(std::move(g));
    q.floor.push_back(low);
    q.top.push_back(high);
    q.slope_low.push_back(inv_sd(low));
    q.slope_high.push_back(inv_sd(high));
  }
  const std::size_t width = bands * bins;
  q.width = width;
  const auto transformed = [&](std::size_t e, double* y, double* dy) {
    for (std::size_t k = 0; k < bands; ++k) {
      double* yk = y + k * bins;
      double* dk = dy + k * bins;
      for (std::size_t j = 0; j < bins; ++j) yk[j] = q.transform(k, emulated_[e][k][j]);
      dk[0] = dk[bins - 1] = 0.0;
      for (std::size_t j = 1; j + 1 < bins; ++j) dk[j] = 0.5 * (yk[j + 1] - yk[j - 1]);
    }
  };
  Eigen::VectorXd y(width), dy(width), mean = Eigen::VectorXd::Zero(width);
  for (std::size_t e = 0; e < entries; ++e) {
    transformed(e, y.data(), dy.data());
    mean += y;
  }
  mean /= static_cast<double>(entries);
  const std::size_t stride = (entries + 1499) / 1500;
  const std::size_t rows = (entries + stride - 1) / stride;
  Eigen::MatrixXd x(2 * rows, width);
  for (std::size_t r = 0; r < rows; ++r) {
    transformed(r * stride, y.data(), dy.data());
    x.row(2 * r) = (y - mean).transpose();
    x.row(2 * r + 1) = dy.transpose();
  }
  Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(width, width);
  gram.selfadjointView<Eigen::Lower>().rankUpdate(x.transpose());
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(gram);
  const std::size_t components = std::min<std::size_t>(
      {static_cast<std::size_t>(std::max(1, settings_.projection_components)), width, 2 * rows});
  q.components = components;
  // Eigen orders the eigenvalues increasing: the last columns lead.
  const Eigen::MatrixXd basis = eigen.eigenvectors().rightCols(components).rowwise().reverse();
  q.mean.assign(mean.data(), mean.data() + width);
  q.basis.assign(basis.data(), basis.data() + width * components);
  q.coords.resize(entries * components);
  q.slope_coords.resize(entries * components);
  q.residual.resize(entries);
  q.slope_norm2.resize(entries);
  q.scale.resize(entries);
  q.log_det.resize(entries);
  RtPreparedShot level;
  level.noise2 = noise2;
  for (std::size_t e = 0; e < entries; ++e) {
    transformed(e, y.data(), dy.data());
    y -= mean;
    const Eigen::VectorXd ce = basis.transpose() * y, de = basis.transpose() * dy;
    std::copy(ce.data(), ce.data() + components, q.coords.begin() + e * components);
    std::copy(de.data(), de.data() + components, q.slope_coords.begin() + e * components);
    q.residual[e] = std::sqrt(std::max(0.0, y.squaredNorm() - ce.squaredNorm()));
    q.slope_norm2[e] = de.squaredNorm();
    // chi2 under the entry's own emulator variance against the median's, at half its peak.
    const double half = 0.5 * *std::max_element(emulated_[e][0].begin(), emulated_[e][0].end());
    const double v =
        var_linear_[0] * std::max(half, signal_floor_W_[0]) + var_quadratic_[0] * half * half;
    const double rho = measured_factor_ + leverage_[e] * per_entry;
    q.scale[e] = (noise2[0] + rho_ref * v) / std::max(noise2[0] + rho * v, 1e-300);
    q.log_det[e] = log_det(level, e);
  }
  return out;
}

std::vector<std::size_t> RtInversion::prefilter(const RtPreparedShot& p, int shift,
                                                std::int64_t excluded, bool* ok) const {
  const std::size_t entries = table_.entries(), bins = table_.height_m.size();
  const long long n = static_cast<long long>(p.measured[0].size());
  *ok = shift >= 0 && shift + static_cast<long long>(bins) <= n;
  if (!*ok) return {};
  const Projection& q = projection(p);
  const std::size_t components = q.components;
  std::vector<double> y(q.width);
  double y2 = 0.0;
  for (std::size_t k = 0; k < p.measured.size(); ++k) {
    for (std::size_t j = 0; j < bins; ++j) {
      const std::size_t i = k * bins + j;
      y[i] = q.transform(k, p.measured[k][j + shift]) - q.mean[i];
      y2 += y[i] * y[i];
    }
  }
  std::vector<double> cm(components, 0.0);
  double c2 = 0.0;
  for (std::size_t c = 0; c < components; ++c) {
    const double* b = q.basis.data() + c * q.width;
    double sum = 0.0;
    for (std::size_t i = 0; i < q.width; ++i) sum += b[i] * y[i];
    cm[c] = sum;
    c2 += sum * sum;
  }
  const double rm = std::sqrt(std::max(0.0, y2 - c2));
  // Per entry: chi2 ~ |c_m - c_e + delta c'_e|^2 + |r_m - r_e|^2, delta in [-1/2, 1/2] at the
  // first order's minimum; the residuals' cross term bounded either way.
  std::vector<double> lower(entries);
  double best_upper = std::numeric_limits<double>::infinity();
  for (std::size_t e = 0; e < entries; ++e) {
    const double* ce = q.coords.data() + e * components;
    const double* de = q.slope_coords.data() + e * components;
    double a = 0.0, b = 0.0;
    for (std::size_t c = 0; c < components; ++c) {
      const double d = cm[c] - ce[c];
      a += d * d;
      b += d * de[c];
    }
    const double cc = q.slope_norm2[e];
    const double delta = cc > 0.0 ? std::clamp(-b / cc, -0.5, 0.5) : 0.0;
    const double d = a + delta * (2.0 * b + delta * cc);
    const double re = q.residual[e];
    lower[e] = q.scale[e] * (d + (rm - re) * (rm - re)) + q.log_det[e];
    if (static_cast<std::int64_t>(e) != excluded)
      best_upper = std::min(best_upper, q.scale[e] * (d + (rm + re) * (rm + re)) + q.log_det[e]);
  }
  const double reach =
      best_upper + 2.0 * tempering_ *
                       (settings_.prune_log_likelihood + settings_.prefilter_margin_log_likelihood);
  std::vector<std::size_t> kept;
  for (std::size_t e = 0; e < entries; ++e)
    if (static_cast<std::int64_t>(e) != excluded && lower[e] <= reach) kept.push_back(e);
  return kept;
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
  r.canopy_height_m = weighted_statistic(table_.canopy_height_true_m, entry_weight, sorted_[0]);
  r.cover = weighted_statistic(table_.cover_true, entry_weight, sorted_[1]);
  r.pai = weighted_statistic(table_.pai_true, entry_weight, sorted_[2]);
  r.rhov_rhog = weighted_statistic(table_.rhov_rhog, entry_weight, sorted_[3]);
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

// tau: each of up to calibration_shots entries' first shot (displaced by a sub-bin offset from
// a golden-ratio sequence, linearly interpolated) retrieved from the other entries, ground
// searched; the emulator's neighbours that used the entry's mean use its other shots' instead.
// tau starts from the pulse's correlation length and is multiplied by p90(z^2) / 2.706 over the
// varied ranges' z = (truth - mean) / sd (the 90 % interval the product states), up to 6 times,
// the shots whose truth lies in the outer edge_fraction of a range left out.
void RtInversion::calibrate_tempering() {
  const ForwardTable& t = table_;
  const std::size_t entries = t.entries(), bands = t.bands(), bins = t.height_m.size();
  const std::size_t shots =
      std::min<std::size_t>(std::max(1, settings_.calibration_shots), entries);
  const double kk = static_cast<double>(std::max<std::int64_t>(2, t.shots_per_entry));
  std::vector<std::vector<std::pair<std::uint32_t, double>>> users(entries);
  for (std::size_t e = 0; e < entries; ++e)
    for (const auto& [f, w] : smoother_[e]) users[f].push_back({static_cast<std::uint32_t>(e), w});
  struct Case {
    std::size_t entry;
    std::vector<std::vector<double>> waveform;
    std::vector<std::vector<std::vector<double>>> t_override, s_override, c_override;
    std::vector<std::uint32_t> user_ids;
  };
  std::vector<Case> cases;
  for (std::size_t i = 0; i < shots; ++i) {
    Case c;
    c.entry = i * entries / shots;
    bool inside = true;
    for (std::size_t q = 0; q < t.parameters.size(); ++q) inside = inside && edge_[c.entry][q] == 0;
    if (!inside) continue;
    const double phase = std::fmod(0.6180339887498949 * static_cast<double>(i + 1), 1.0) - 0.5;
    for (std::size_t k = 0; k < bands; ++k) {
      const std::vector<double>& w0 = t.shot0_W[c.entry][k];
      std::vector<double> w(bins, 0.0);
      for (std::size_t b = 0; b < bins; ++b) {
        const double x = static_cast<double>(b) - phase;
        const long long lo = static_cast<long long>(std::floor(x));
        const double f = x - static_cast<double>(lo);
        const double a = lo >= 0 && lo < static_cast<long long>(bins) ? w0[lo] : 0.0;
        const double bb = lo + 1 >= 0 && lo + 1 < static_cast<long long>(bins) ? w0[lo + 1] : 0.0;
        w[b] = (1.0 - f) * a + f * bb;
      }
      c.waveform.push_back(std::move(w));
    }
    for (const auto& [user, weight] : users[c.entry]) {
      if (user == c.entry) continue;
      std::vector<std::vector<double>> tt(bands), ss(bands), cc(bands);
      for (std::size_t k = 0; k < bands; ++k) {
        tt[k] = emulated_[user][k];
        for (std::size_t j = 0; j < bins; ++j) {
          const double others =
              (kk * t.waveform_W[c.entry][k][j] - t.shot0_W[c.entry][k][j]) / (kk - 1.0);
          tt[k][j] = std::max(0.0, tt[k][j] + weight * (others - t.waveform_W[c.entry][k][j]));
        }
        ss[k].assign(bins, 0.0);
        cc[k].assign(bins, 0.0);
        for (std::size_t j = 1; j + 1 < bins; ++j) {
          ss[k][j] = 0.5 * (tt[k][j + 1] - tt[k][j - 1]);
          cc[k][j] = tt[k][j + 1] - 2.0 * tt[k][j] + tt[k][j - 1];
        }
      }
      c.t_override.push_back(std::move(tt));
      c.s_override.push_back(std::move(ss));
      c.c_override.push_back(std::move(cc));
      c.user_ids.push_back(user);
    }
    cases.push_back(std::move(c));
  }
  if (cases.size() < 5) return;
  std::vector<std::size_t> ranges;
  for (std::size_t q = 0; q < t.parameters.size(); ++q)
    if (t.parameters[q].is_range() && t.parameters[q].high > t.parameters[q].low)
      ranges.push_back(q);
  if (ranges.empty()) return;
  // The first shot is a simulated shot of the table's rays, whatever the measured shots are.
  const double measured = measured_factor_;
  if (measured != 1.0) {
    measured_factor_ = 1.0;
    build_variances();
  }
  // Start from the correlation's own count: a Gaussian pulse of sigma bins correlates the
  // bins' noise as exp(-d^2 / 4 sigma^2), whose sum over lags is 2 sqrt(pi) sigma.
  tempering_ = std::max(1.0, 2.0 * std::sqrt(std::numbers::pi) * t.pulse_sigma_ns / t.bin_ns);
  for (int round = 0; round < 6; ++round) {
    std::vector<double> z2;
    for (const Case& c : cases) {
      RtShot shot;
      for (const auto& w : c.waveform) shot.waveform.emplace_back(w);
      shot.axis = {t.bin_ns, t.height_m.front(), t.height_m.back()};
      shot.noise_mean_W.assign(bands, 0.0);
      shot.noise_sd_W.assign(bands, 0.0);
      shot.ground_guess_m = 0.0;
      const RtPreparedShot p = prepare_window(shot, 0, 3);
      if (!p.usable) continue;
      std::vector<std::vector<EntryBand>> views(c.user_ids.size(), std::vector<EntryBand>(bands));
      std::vector<const EntryBand*> override(entries, nullptr);
      for (std::size_t u = 0; u < c.user_ids.size(); ++u) {
        for (std::size_t k = 0; k < bands; ++k)
          views[u][k] = {c.t_override[u][k].data(), c.s_override[u][k].data(),
                         c.c_override[u][k].data()};
        override[c.user_ids[u]] = views[u].data();
      }
      bool edge = false;
      const std::vector<Cell> cells =
          search(p, static_cast<std::int64_t>(c.entry), override, &edge);
      if (cells.empty()) continue;
      double top = -std::numeric_limits<double>::infinity();
      for (const Cell& cell : cells) top = std::max(top, cell.log_likelihood);
      std::vector<double> weight(entries, 0.0);
      for (const Cell& cell : cells) weight[cell.entry] += std::exp(cell.log_likelihood - top);
      for (std::size_t q : ranges) {
        double sw = 0, s1 = 0, s2 = 0;
        for (std::size_t e = 0; e < entries; ++e) {
          sw += weight[e];
          s1 += weight[e] * t.parameter_values[e][q];
        }
        const double mean = s1 / sw;
        for (std::size_t e = 0; e < entries; ++e)
          s2 += weight[e] * std::pow(t.parameter_values[e][q] - mean, 2);
        const double sd = std::sqrt(s2 / sw);
        // A posterior narrower than the design's spacing cannot say how wrong it is.
        const double z = (t.parameter_values[c.entry][q] - mean) / std::max(sd, 1e-12);
        z2.push_back(z * z);
      }
    }
    if (z2.size() < 5) break;
    std::sort(z2.begin(), z2.end());
    const double ratio = z2[z2.size() * 9 / 10] / kP90Chi2One;
    if (std::abs(ratio - 1.0) < 0.05) break;
    tempering_ = std::clamp(tempering_ * ratio, 0.1, 1e4);
  }
  if (measured != 1.0) {
    measured_factor_ = measured;
    build_variances();
  }
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
