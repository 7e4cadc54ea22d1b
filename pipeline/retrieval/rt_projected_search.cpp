// The rt inversion's projected search (RtSearch::projected, rt_inversion.hpp says how): the
// transformed entries' principal components, one set per quarter octave of detector noise, and
// the prefilter that bounds each entry's chi2 through them.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>

#include "pipeline/retrieval/rt_inversion.hpp"

namespace glaswave {

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
    q.no_signal.push_back(q.transform(k, 0.0));
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
  q.beyond_prefix.resize(entries * bands * (bins + 1));
  for (std::size_t e = 0; e < entries; ++e) {
    transformed(e, y.data(), dy.data());
    for (std::size_t k = 0; k < bands; ++k) {
      const double g0 = q.no_signal[k];
      double* prefix = q.beyond_prefix.data() + (e * bands + k) * (bins + 1);
      prefix[0] = 0.0;
      for (std::size_t j = 0; j < bins; ++j)
        prefix[j + 1] = prefix[j] + (g0 - y[k * bins + j]) * (g0 - y[k * bins + j]);
    }
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
    q.log_det[e] = log_det(noise2, e);
  }
  return out;
}

std::vector<std::size_t> RtInversion::prefilter(const RtPreparedShot& p, int shift,
                                                std::int64_t excluded, bool* ok) const {
  const std::size_t entries = table_.entries(), bins = table_.height_m.size();
  const long long n = static_cast<long long>(p.measured[0].size());
  // The window's bins [first, last) hold the shot's; those beyond it (a window overhanging the
  // shot's end, as a table reaching far below the ground does) are taken as no signal, and what
  // they add to each entry's distance is taken off its bounds: the exact chi2 counts the shot's
  // bins only.
  const long long first = std::clamp<long long>(-shift, 0, static_cast<long long>(bins));
  const long long last = std::clamp<long long>(n - shift, 0, static_cast<long long>(bins));
  *ok = first < last;
  if (!*ok) return {};
  const Projection& q = projection(p);
  const std::size_t components = q.components, bands = p.measured.size();
  std::vector<double> y(q.width);
  double y2 = 0.0;
  for (std::size_t k = 0; k < bands; ++k) {
    const double g0 = q.no_signal[k];
    for (std::size_t j = 0; j < bins; ++j) {
      const std::size_t i = k * bins + j;
      const long long at = static_cast<long long>(j);
      y[i] = (at >= first && at < last ? q.transform(k, p.measured[k][j + shift]) : g0) - q.mean[i];
      y2 += y[i] * y[i];
    }
  }
  const bool overhangs = first > 0 || last < static_cast<long long>(bins);
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
    double beyond = 0.0;
    if (overhangs) {
      for (std::size_t k = 0; k < bands; ++k) {
        const double* prefix = q.beyond_prefix.data() + (e * bands + k) * (bins + 1);
        beyond += prefix[first] + (prefix[bins] - prefix[last]);
      }
    }
    lower[e] = q.scale[e] * (d + (rm - re) * (rm - re) - beyond) + q.log_det[e];
    if (static_cast<std::int64_t>(e) != excluded)
      best_upper =
          std::min(best_upper, q.scale[e] * (d + (rm + re) * (rm + re) - beyond) + q.log_det[e]);
  }
  const double reach =
      best_upper + 2.0 * tempering_ *
                       (settings_.prune_log_likelihood + settings_.prefilter_margin_log_likelihood);
  std::vector<std::size_t> kept;
  for (std::size_t e = 0; e < entries; ++e)
    if (static_cast<std::int64_t>(e) != excluded && lower[e] <= reach) kept.push_back(e);
  return kept;
}

}  // namespace glaswave
