// What the rt inversion learns from its forward table before any shot: each entry's support and
// the entries' order by each variable and place in the design, and for the calibrated likelihood
// the local linear emulator, the noise model v(T), the variances and their log-determinants, and
// the tempering tau calibrated on the table's own first shots (rt_inversion.hpp says how).
#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>

#include "pipeline/retrieval/rt_inversion.hpp"

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

// The grid of detector noise variances on which sum log V is tabulated: u_out 2^(g - 24).
constexpr int kLogDetGrid = 40, kLogDetGridLow = -24;
// The 90th percentile of a chi-squared variable of one degree of freedom: a Gaussian z's 90 %
// interval is |z| < 1.645.
constexpr double kP90Chi2One = 2.705543;

}  // namespace

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
  pgap_true_ = table.pgap_true.size() == entries
                   ? table.pgap_true
                   : std::vector<double>(entries, std::numeric_limits<double>::quiet_NaN());
  truths_ = {&table.canopy_height_true_m, &table.cover_true, &table.pai_true, &table.rhov_rhog,
             &pgap_true_};
  for (const std::vector<double>* v : truths_) {
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

double RtInversion::log_det(const std::vector<double>& noise2, std::size_t entry) const {
  double sum = 0.0;
  for (std::size_t b = 0; b < noise2.size(); ++b) {
    const std::vector<double>& grid = log_det_grid_[entry][b];
    const double n2 = noise2[b];
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

// tau: each of up to calibration_shots entries' first shot (displaced by a sub-bin offset from
// a golden-ratio sequence, linearly interpolated) retrieved from the other entries, ground
// searched; the emulator's neighbours that used the entry's mean use its other shots' instead.
// tau starts from the pulse's correlation length and is multiplied by p90(z^2) / 2.706 over the
// varied ranges' z = (truth - mean) / sd (the 90 % interval the product states), up to 6 times,
// the shots whose truth lies in the outer edge_fraction of a range left out.
double RtInversion::standardised_error(const std::vector<double>& weight, std::size_t parameter,
                                       std::size_t entry) const {
  const ForwardTable& t = table_;
  double sw = 0, s1 = 0, s2 = 0;
  for (std::size_t e = 0; e < t.entries(); ++e) {
    sw += weight[e];
    s1 += weight[e] * t.parameter_values[e][parameter];
  }
  const double mean = s1 / sw;
  for (std::size_t e = 0; e < t.entries(); ++e)
    s2 += weight[e] * std::pow(t.parameter_values[e][parameter] - mean, 2);
  // A posterior narrower than the design's spacing cannot say how wrong it is.
  return (t.parameter_values[entry][parameter] - mean) / std::max(std::sqrt(s2 / sw), 1e-12);
}

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
  // Every entry's terms for shots without detector noise, shared by the cases' searches.
  const std::vector<double> no_noise(bands, 0.0);
  std::vector<EntryTerms> shared(entries);
  for (std::size_t e = 0; e < entries; ++e)
    entry_terms(no_noise, e, own_bands(e).data(), shared[e]);
  for (int round = 0; round < 6; ++round) {
    // The cases in parallel (the caller's arena: --threads), each its own z^2, sorted together.
    std::vector<std::vector<double>> z2_of(cases.size());
    tbb::parallel_for(std::size_t{0}, cases.size(), [&](std::size_t i) {
      const Case& c = cases[i];
      RtShot shot;
      for (const auto& w : c.waveform) shot.waveform.emplace_back(w);
      shot.axis = {t.bin_ns, t.height_m.front(), t.height_m.back()};
      shot.noise_mean_W.assign(bands, 0.0);
      shot.noise_sd_W.assign(bands, 0.0);
      shot.ground_guess_m = 0.0;
      const RtPreparedShot p = prepare_window(shot, 0, 3);
      if (!p.usable) return;
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
          search(p, static_cast<std::int64_t>(c.entry), override, &edge, &shared);
      if (cells.empty()) return;
      double top = -std::numeric_limits<double>::infinity();
      for (const Cell& cell : cells) top = std::max(top, cell.log_likelihood);
      std::vector<double> weight(entries, 0.0);
      for (const Cell& cell : cells) weight[cell.entry] += std::exp(cell.log_likelihood - top);
      for (std::size_t q : ranges) {
        const double z = standardised_error(weight, q, c.entry);
        z2_of[i].push_back(z * z);
      }
    });
    std::vector<double> z2;
    for (const std::vector<double>& z : z2_of) z2.insert(z2.end(), z.begin(), z.end());
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

}  // namespace glaswave
