// Gaussian decomposition: first guesses from the curvature of the smoothed waveform, a small
// Levenberg-Marquardt fit of our own (analytic Jacobian, normal equations in fixed arrays, over
// the signal's window only), then components added from the residual and pruned.
#include "pipeline/products/gaussian_decomposition.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <tuple>
#include <utility>

namespace glaswave {
namespace {

// Beyond this many sigma a Gaussian is below 1e-14 of its peak: taken as 0, which spares most
// of the exponentials of a narrow component over a long window.
constexpr double kCutoffSigmas = 8.0;
constexpr int kMaxParameters = 3 * kMaxFitComponents;
// Jacobian evaluations per fit: a fit from fair guesses converges in 5 to 20; the cap bounds
// the cost of a hopeless one.
constexpr int kMaxIterations = 40;
// A bin's error variance is taken as at least this part of the window's largest: a bin that no
// ray reached has its variance estimated 0 where the model's tail may still be, and the fit,
// unweighted, spreads its residual more evenly than the noise. (At 0.03, 1 in 20 bare 20 degree
// slopes at 300 rays still split; the price: a weak ground under a dense canopy at a few
// hundred rays may not stand out of the canopy's noise.)
constexpr double kVarianceFloor = 0.1;

using Vector = std::array<double, kMaxParameters>;
using Matrix = std::array<std::array<double, kMaxParameters>, kMaxParameters>;

// The fit's problem: data scaled to order 1 over bins first..last, p = 3 * components
// parameters (amplitude, centre, sigma of each), and the Gaussians' unit profiles at the point
// last evaluated (exp[k * bins + i - first]; zero beyond the cutoff), allocated once per fit.
struct Problem {
  std::span<const double> values;
  int first = 0, last = 0, p = 0;
  double inverse_scale = 1.0;
  std::vector<double> profile;
  std::array<int, kMaxFitComponents> lo{}, hi{};  // each component's bins within the cutoff

  int bins() const { return last - first + 1; }
};

// Adds amplitude exp(-(i - center)^2 / (2 sigma^2)) to out[i - offset] over the bins of lo..hi
// within the cutoff, by the recurrence g(i + 1) = g(i) r(i), r(i + 1) = r(i) exp(-1 / sigma^2):
// three exponentials instead of one per bin (the round-off over a few hundred bins stays near
// 1e-14). Returns the bins it covered (lo > hi: none). A width that is not positive, or a value
// that is not finite, is evaluated bin by bin as the Gaussian's formula gives it.
std::pair<int, int> add_profile(double* out, int offset, int lo, int hi, double amplitude,
                                double center, double sigma) {
  if (!(sigma > 0.0) || !std::isfinite(sigma) || !std::isfinite(center) ||
      !std::isfinite(amplitude)) {
    const GaussianComponent g{amplitude, center, sigma};
    for (int i = lo; i <= hi; ++i) out[i - offset] += g.value_at(i);
    return {lo, hi};
  }
  // Clipped as doubles: a centre far outside the bins would not fit an int.
  const double reach = kCutoffSigmas * sigma;
  const double from = std::max<double>(lo, std::ceil(center - reach));
  const double to = std::min<double>(hi, std::floor(center + reach));
  if (!(from <= to)) return {hi + 1, hi};
  lo = static_cast<int>(from);
  hi = static_cast<int>(to);
  const double inverse_variance = 1.0 / (sigma * sigma);
  const double d = lo - center;
  double g = std::exp(-0.5 * d * d * inverse_variance);
  double ratio = std::exp(-(d + 0.5) * inverse_variance);
  const double step = std::exp(-inverse_variance);
  for (int i = lo; i <= hi; ++i) {
    out[i - offset] += amplitude * g;
    g *= ratio;
    ratio *= step;
  }
  return {lo, hi};
}

// Fills component k's unit profile over its reach (zero beyond the cutoff).
void fill_profile(Problem& problem, int k, double center, double sigma) {
  double* e = problem.profile.data() + static_cast<std::size_t>(k) * problem.bins();
  std::fill(e, e + problem.bins(), 0.0);
  std::tie(problem.lo[k], problem.hi[k]) =
      add_profile(e, problem.first, problem.first, problem.last, 1.0, center, sigma);
}

// Sum of squared residuals at x, the profiles left at x; +inf when a width is not positive or a
// value not finite.
double cost(Problem& problem, const Vector& x) {
  for (int k = 0; k < problem.p; k += 3)
    if (!(x[k + 2] > 1e-3) || !std::isfinite(x[k]) || !std::isfinite(x[k + 1]))
      return std::numeric_limits<double>::infinity();
  for (int k = 0; k < problem.p / 3; ++k) fill_profile(problem, k, x[3 * k + 1], x[3 * k + 2]);
  const int n = problem.bins();
  double sum = 0.0;
  for (int j = 0; j < n; ++j) {
    double model = 0.0;
    for (int k = 0; k < problem.p / 3; ++k) model += x[3 * k] * problem.profile[k * n + j];
    const double r = model - problem.values[problem.first + j] * problem.inverse_scale;
    sum += r * r;
  }
  return sum;
}

// A component's row of the Jacobian at bin i, the model's derivatives by its amplitude, centre
// and sigma, from its unit profile e there and its 1 / sigma.
std::array<double, 3> jacobian_row(double amplitude, double center, double inverse_sigma, double e,
                                   int i) {
  const double u = (i - center) * inverse_sigma;
  const double d_center = amplitude * e * u * inverse_sigma;
  return {e, d_center, d_center * u};
}

// J^T J (upper triangle) and J^T r at x (whose profiles the problem holds), one bin's row at a
// time: only the parameters of the components within reach of the bin take part, and bins beyond
// every component's reach add nothing. One component (a bare slope's broad return, the most bins
// to cover) is summed in registers.
void normal_equations(const Problem& problem, const Vector& x, Matrix& jtj, Vector& jtr) {
  for (int a = 0; a < problem.p; ++a) {
    jtr[a] = 0.0;
    for (int b = a; b < problem.p; ++b) jtj[a][b] = 0.0;
  }
  const int n = problem.bins();
  const int components = problem.p / 3;
  std::array<double, kMaxFitComponents> inverse_sigma{};
  int lo = problem.last + 1, hi = problem.first - 1;
  for (int k = 0; k < components; ++k) {
    inverse_sigma[k] = 1.0 / x[3 * k + 2];
    lo = std::min(lo, problem.lo[k]);
    hi = std::max(hi, problem.hi[k]);
  }
  const double* values = problem.values.data();
  if (components == 1) {
    const double a = x[0], c = x[1], w = inverse_sigma[0];
    const double* e = problem.profile.data();
    double aa = 0.0, ac = 0.0, as = 0.0, cc = 0.0, cs = 0.0, ss = 0.0;
    double ra = 0.0, rc = 0.0, rs = 0.0;
    for (int i = lo; i <= hi; ++i) {
      const double g = e[i - problem.first];
      const auto [ja, jc, js] = jacobian_row(a, c, w, g, i);
      const double r = a * g - values[i] * problem.inverse_scale;
      aa += ja * ja, ac += ja * jc, as += ja * js;
      cc += jc * jc, cs += jc * js, ss += js * js;
      ra += ja * r, rc += jc * r, rs += js * r;
    }
    jtj[0][0] = aa, jtj[0][1] = ac, jtj[0][2] = as;
    jtj[1][1] = cc, jtj[1][2] = cs, jtj[2][2] = ss;
    jtr[0] = ra, jtr[1] = rc, jtr[2] = rs;
    return;
  }
  std::array<double, kMaxParameters> row{};
  std::array<int, kMaxParameters> index{};
  for (int i = lo; i <= hi; ++i) {
    int active = 0;
    double model = 0.0;
    for (int k = 0; k < components; ++k) {
      if (i < problem.lo[k] || i > problem.hi[k]) continue;
      const double e = problem.profile[k * n + i - problem.first];
      model += x[3 * k] * e;
      const std::array<double, 3> j = jacobian_row(x[3 * k], x[3 * k + 1], inverse_sigma[k], e, i);
      for (int d = 0; d < 3; ++d) row[active] = j[d], index[active++] = 3 * k + d;
    }
    const double r = model - values[i] * problem.inverse_scale;
    for (int m = 0; m < active; ++m) {
      jtr[index[m]] += row[m] * r;
      for (int q = m; q < active; ++q) jtj[index[m]][index[q]] += row[m] * row[q];
    }
  }
}

// Solves (J^T J + lambda D) delta = -J^T r by Cholesky; false when not positive definite.
bool solve_step(const Matrix& jtj, const Vector& jtr, const Vector& diagonal, double lambda, int p,
                Vector& delta) {
  Matrix l{};
  for (int a = 0; a < p; ++a) {
    for (int b = 0; b <= a; ++b) {
      double sum = b == a ? jtj[a][a] + lambda * diagonal[a] : jtj[b][a];
      for (int c = 0; c < b; ++c) sum -= l[a][c] * l[b][c];
      if (b == a) {
        if (!(sum > 0.0)) return false;
        l[a][a] = std::sqrt(sum);
      } else {
        l[a][b] = sum / l[b][b];
      }
    }
  }
  Vector z{};
  for (int a = 0; a < p; ++a) {
    double sum = -jtr[a];
    for (int c = 0; c < a; ++c) sum -= l[a][c] * z[c];
    z[a] = sum / l[a][a];
  }
  for (int a = p - 1; a >= 0; --a) {
    double sum = z[a];
    for (int c = a + 1; c < p; ++c) sum -= l[c][a] * delta[c];
    delta[a] = sum / l[a][a];
  }
  return true;
}

// Levenberg-Marquardt with Moré's scaling (the largest diagonal of J^T J seen so far): a
// rejected step raises lambda and tries again with the same Jacobian. Stops when a step moves
// every parameter by less than 1e-8 of itself (far finer than a waveform resolves), when the
// cost stops falling, or at the cap.
void levenberg_marquardt(Problem& problem, Vector& x) {
  Matrix jtj{};
  Vector jtr{}, diagonal{}, delta{}, trial{};
  double current = cost(problem, x);
  if (!std::isfinite(current)) return;
  double lambda = 1e-3;
  for (int iteration = 0; iteration < kMaxIterations; ++iteration) {
    normal_equations(problem, x, jtj, jtr);
    for (int a = 0; a < problem.p; ++a) diagonal[a] = std::max(diagonal[a], jtj[a][a]);
    bool accepted = false, converged = false;
    for (int attempt = 0; attempt < 12 && !accepted; ++attempt) {
      if (solve_step(jtj, jtr, diagonal, lambda, problem.p, delta)) {
        converged = true;
        for (int a = 0; a < problem.p; ++a) {
          trial[a] = x[a] + delta[a];
          if (std::abs(delta[a]) > 1e-8 * (std::abs(x[a]) + 1e-8)) converged = false;
        }
        const double next = cost(problem, trial);
        if (next <= current) {
          accepted = true;
          // Less than 1e-6 of the misfit gained: as good as the data allows.
          const bool stalled = next > current * (1.0 - 1e-6);
          x = trial;
          current = next;
          lambda = std::max(lambda / 3.0, 1e-12);
          if (stalled) converged = true;
          break;
        }
      }
      if (converged) break;
      lambda *= 4.0;
    }
    if (!accepted || converged) return;
  }
}

// values - the components' sum, over bins lo..hi (residual[i - lo]).
std::vector<double> residual_over(std::span<const double> values, int lo, int hi,
                                  const std::vector<GaussianComponent>& components) {
  std::vector<double> model(hi - lo + 1, 0.0);
  for (const GaussianComponent& g : components)
    add_profile(model.data(), lo, lo, hi, g.amplitude, g.center_bin, g.sigma_bins);
  for (int i = lo; i <= hi; ++i) model[i - lo] = values[i] - model[i - lo];
  return model;
}

double sum_of_squares(std::span<const double> values, int first, int last,
                      const std::vector<GaussianComponent>& components) {
  double sum = 0.0;
  for (double r : residual_over(values, first, last, components)) sum += r * r;
  return sum;
}

// The misfit in units of the noise: the sum of r^2 over each bin's error variance, floored at
// a tenth of the window's largest. The floor bounds the weight of a bin that no ray reached
// (its variance estimated 0, where the model's tail may still be), and keeps an unweighted
// fit's residuals, which spread more evenly than the noise, from swamping the test.
double chi_square(std::span<const double> values, int first, int last,
                  const std::vector<GaussianComponent>& components,
                  std::span<const double> variance) {
  const double floor =
      kVarianceFloor * *std::max_element(variance.begin() + first, variance.begin() + last + 1);
  const std::vector<double> residual = residual_over(values, first, last, components);
  double sum = 0.0;
  for (int i = first; i <= last; ++i) {
    const double r = residual[i - first];
    sum += r * r / std::max(variance[i], floor);
  }
  return sum;
}

// What a guess alone could take off chi^2 with only its amplitude free, the others held: the
// weighted projection of the residual on its shape, (sum w r g)^2 / sum w g^2. A fit of all
// gains more where the others make room, but a bump of noise stays far below the test.
// `residual` holds values - model from bin `offset` on, over first..last at least.
double linear_gain(std::span<const double> residual, int offset, int first, int last,
                   const GaussianComponent& guess, std::span<const double> variance) {
  const double floor =
      kVarianceFloor * *std::max_element(variance.begin() + first, variance.begin() + last + 1);
  const int lo = std::max(first, static_cast<int>(guess.center_bin - 5.0 * guess.sigma_bins));
  const int hi = std::min(last, static_cast<int>(guess.center_bin + 5.0 * guess.sigma_bins));
  if (lo > hi) return 0.0;
  std::vector<double> unit(hi - lo + 1, 0.0);
  add_profile(unit.data(), lo, lo, hi, 1.0, guess.center_bin, guess.sigma_bins);
  double cross = 0.0, norm = 0.0;
  for (int i = lo; i <= hi; ++i) {
    const double g = unit[i - lo], w = 1.0 / std::max(variance[i], floor);
    cross += w * residual[i - offset] * g;
    norm += w * g * g;
  }
  return cross > 0.0 && norm > 0.0 ? cross * cross / norm : 0.0;
}

// A smoothed Gaussian of seen width `seen` with the filter taken out, never narrower than the
// pulse allows; its amplitude undoes the filter's lowering of the peak (sigma / seen).
GaussianComponent unsmoothed(double smoothed_amplitude, double center_bin, double seen,
                             const DecompositionSettings& settings) {
  const double filter = settings.smooth_sigma_bins;
  const double sigma = std::sqrt(std::max(seen * seen - filter * filter,
                                          1.2 * settings.min_sigma_bins * settings.min_sigma_bins));
  return {smoothed_amplitude * std::sqrt(sigma * sigma + filter * filter) / sigma, center_bin,
          sigma};
}

// The peak of a component as the smoothing filter shows it: what the threshold is compared with.
double smoothed_peak(const GaussianComponent& g, double filter_sigma) {
  return g.amplitude * g.sigma_bins / std::hypot(g.sigma_bins, filter_sigma);
}

}  // namespace

double GaussianComponent::area() const {
  return amplitude * sigma_bins * std::sqrt(2.0 * std::numbers::pi);
}

double GaussianComponent::value_at(double x) const {
  const double u = (x - center_bin) / sigma_bins;
  return amplitude * std::exp(-0.5 * u * u);
}

std::vector<double> gaussian_smooth(std::span<const double> values, double sigma_bins) {
  const int n = static_cast<int>(values.size());
  if (sigma_bins <= 0.0 || n == 0) return {values.begin(), values.end()};
  const int half = std::max(1, static_cast<int>(std::ceil(4.0 * sigma_bins)));
  std::vector<double> kernel(2 * half + 1);
  for (int k = -half; k <= half; ++k)
    kernel[k + half] = std::exp(-0.5 * (k / sigma_bins) * (k / sigma_bins));
  // Bins farther than `half` from every nonzero value stay 0, as the sum over zeros would give
  // (a short shot's waveform is mostly zeros).
  int first_nonzero = n, last_nonzero = -1;
  for (int i = 0; i < n; ++i) {
    if (values[i] != 0.0) {
      first_nonzero = std::min(first_nonzero, i);
      last_nonzero = i;
    }
  }
  std::vector<double> out(n, 0.0);
  // Bin i alone: the kernel cut at the ends, renormalised.
  auto smooth_one = [&](int i) {
    double sum = 0.0, weight = 0.0;
    for (int k = std::max(-half, -i); k <= std::min(half, n - 1 - i); ++k) {
      sum += kernel[k + half] * values[i + k];
      weight += kernel[k + half];
    }
    out[i] = sum / weight;
  };
  // Away from the ends every bin has the whole kernel, and the same weight: four bins at a time,
  // each summed in the same order as alone.
  double whole_weight = 0.0;
  for (double weight : kernel) whole_weight += weight;
  const int begin = std::max(0, first_nonzero - half), end = std::min(n, last_nonzero + half + 1);
  int i = begin;
  for (; i < std::min(end, half); ++i) smooth_one(i);
  for (; i + 4 <= std::min(end, n - half); i += 4) {
    const double* first = values.data() + i - half;
    double sum0 = 0.0, sum1 = 0.0, sum2 = 0.0, sum3 = 0.0;
    for (int k = 0; k <= 2 * half; ++k) {
      sum0 += kernel[k] * first[k];
      sum1 += kernel[k] * first[k + 1];
      sum2 += kernel[k] * first[k + 2];
      sum3 += kernel[k] * first[k + 3];
    }
    out[i] = sum0 / whole_weight;
    out[i + 1] = sum1 / whole_weight;
    out[i + 2] = sum2 / whole_weight;
    out[i + 3] = sum3 / whole_weight;
  }
  for (; i < end; ++i) smooth_one(i);
  return out;
}

std::vector<GaussianComponent> fit_gaussians(std::span<const double> values, int first, int last,
                                             const std::vector<GaussianComponent>& initial) {
  const int p = 3 * static_cast<int>(initial.size());
  if (initial.empty() || p > kMaxParameters || last - first + 1 < p || first < 0 ||
      last >= static_cast<int>(values.size()))
    return initial;
  // Scaled to order 1, so that the tolerances mean the same for any power level.
  double scale = 0.0;
  for (int i = first; i <= last; ++i) scale = std::max(scale, std::abs(values[i]));
  if (!(scale > 0.0) || !std::isfinite(scale)) return initial;
  Problem problem{values, first, last, p, 1.0 / scale, {}, {}, {}};
  problem.profile.resize(initial.size() * static_cast<std::size_t>(problem.bins()));
  Vector x{};
  for (std::size_t k = 0; k < initial.size(); ++k) {
    x[3 * k] = initial[k].amplitude / scale;
    x[3 * k + 1] = initial[k].center_bin;
    x[3 * k + 2] = std::abs(initial[k].sigma_bins);
  }
  levenberg_marquardt(problem, x);
  std::vector<GaussianComponent> fitted;
  for (std::size_t k = 0; k < initial.size(); ++k) {
    const GaussianComponent g{x[3 * k] * scale, x[3 * k + 1], std::abs(x[3 * k + 2])};
    if (!std::isfinite(g.amplitude) || !std::isfinite(g.center_bin) || !std::isfinite(g.sigma_bins))
      return initial;
    fitted.push_back(g);
  }
  return fitted;
}

namespace {

// First guesses from the curvature of the smoothed waveform (as GLA14 and GEDI L2A): each
// stretch between two inflection points where it bends down holds one Gaussian, centred where
// it bends most, its width half the distance between the inflections (a Gaussian's inflections
// lie at +-sigma), its height the larger of the smoothed value and the curvature's estimate
// (-s'' sigma^2), never above the value there. A shoulder in a neighbour's flank, which is no
// local maximum, is found as well. Strongest (by area) first, at most max_components; those
// whose height does not clear the level are none.
std::vector<GaussianComponent> curvature_guesses(std::span<const double> smoothed, int first,
                                                 int last, const DecompositionSettings& settings) {
  const int n = static_cast<int>(smoothed.size());
  auto curvature = [&](int i) { return smoothed[i + 1] - 2.0 * smoothed[i] + smoothed[i - 1]; };
  std::vector<GaussianComponent> guesses;
  const int lo = std::max(first, 1), hi = std::min(last, n - 2);
  for (int i = lo; i <= hi; ++i) {
    if (!(curvature(i) < 0.0)) continue;
    const int begin = i;
    int deepest = i;
    while (i + 1 <= hi && curvature(i + 1) < 0.0) {
      ++i;
      if (curvature(i) < curvature(deepest)) deepest = i;
    }
    // Inflections interpolated where the curvature crosses 0 (or the window's edge).
    const double left =
        begin > lo ? begin - 1 + curvature(begin - 1) / (curvature(begin - 1) - curvature(begin))
                   : static_cast<double>(begin);
    const double right =
        i < hi ? i + curvature(i) / (curvature(i) - curvature(i + 1)) : static_cast<double>(i);
    const double seen = std::max(0.5 * (right - left), 0.5);
    // Vertex of a parabola through the curvature's three values about its minimum.
    double center = deepest;
    if (deepest > lo && deepest < hi) {
      const double a = curvature(deepest - 1), b = curvature(deepest), c = curvature(deepest + 1);
      const double denominator = a - 2.0 * b + c;
      if (denominator > 0.0) center += std::clamp(0.5 * (a - c) / denominator, -0.5, 0.5);
    }
    const double height =
        std::min(smoothed[deepest], std::max(-curvature(deepest) * seen * seen, 0.0));
    if (!(height > settings.significance_level)) continue;
    guesses.push_back(unsmoothed(height, center, seen, settings));
  }
  std::sort(
      guesses.begin(), guesses.end(),
      [](const GaussianComponent& a, const GaussianComponent& b) { return a.area() > b.area(); });
  if (static_cast<int>(guesses.size()) > settings.max_components)
    guesses.resize(settings.max_components);
  return guesses;
}

// Half width at half maximum of the peak at `peak` in `s` (the nearer side, since the other
// may run into a neighbouring peak), in bins; the whole range when it never falls to half.
double half_width(std::span<const double> s, int peak, int first, int last) {
  const double half = 0.5 * s[peak];
  double best = static_cast<double>(last - first + 1);
  for (int i = peak - 1; i >= first; --i) {
    if (s[i] <= half) {
      best = std::min(best, peak - i - (half - s[i]) / (s[i + 1] - s[i] + 1e-300));
      break;
    }
  }
  for (int i = peak + 1; i <= last; ++i) {
    if (s[i] <= half) {
      best = std::min(best, i - peak - (half - s[i]) / (s[i - 1] - s[i] + 1e-300));
      break;
    }
  }
  return std::max(best, 0.5);
}

// A guess for the highest bin of a smoothed residual: its width from the half maximum.
GaussianComponent peak_guess(std::span<const double> smoothed, int peak, int first, int last,
                             const DecompositionSettings& settings) {
  const double seen = half_width(smoothed, peak, first, last) / std::sqrt(2.0 * std::numbers::ln2);
  return unsmoothed(smoothed[peak], peak, seen, settings);
}

// Signal the fit leaves in the residual (a peak hidden in its neighbour's flank, most often)
// gets a component of its own, as long as it makes the fit better.
std::vector<GaussianComponent> add_residual_components(std::span<const double> values, int first,
                                                       int last,
                                                       std::vector<GaussianComponent> components,
                                                       const DecompositionSettings& settings) {
  double misfit = sum_of_squares(values, first, last, components);
  // Only the window and the smoothing filter's reach beyond it are needed.
  const int reach = static_cast<int>(std::ceil(4.0 * settings.smooth_sigma_bins));
  const int lo = std::max(first - reach, 0);
  const int hi = std::min(last + reach, static_cast<int>(values.size()) - 1);
  while (static_cast<int>(components.size()) < settings.max_components) {
    const std::vector<double> residual = residual_over(values, lo, hi, components);
    const std::vector<double> smooth_residual =
        gaussian_smooth(residual, settings.smooth_sigma_bins);
    // The highest residual; with the noise known, the one that stands most noise sds high (a
    // weak ground under a noisy canopy before the canopy's larger bumps of noise).
    const std::span<const double> variance = settings.error_variance;
    const double floor = variance.empty()
                             ? 1.0
                             : kVarianceFloor * *std::max_element(variance.begin() + first,
                                                                  variance.begin() + last + 1);
    auto standing = [&](int i) {
      return variance.empty() ? smooth_residual[i - lo]
                              : smooth_residual[i - lo] / std::sqrt(std::max(variance[i], floor));
    };
    int best = first;
    double best_standing = standing(first);
    for (int i = first + 1; i <= last; ++i) {
      const double here = standing(i);
      if (here > best_standing) best = i, best_standing = here;
    }
    if (!(smooth_residual[best - lo] > settings.significance_level)) break;
    std::vector<GaussianComponent> trial = components;
    GaussianComponent added =
        peak_guess(smooth_residual, best - lo, first - lo, last - lo, settings);
    added.center_bin += lo;
    if (!variance.empty() &&
        linear_gain(residual, lo, first, last, added, variance) < 0.5 * settings.min_chi2_gain)
      break;  // noise: not worth a fit
    trial.push_back(added);
    trial = fit_gaussians(values, first, last, trial);
    const double trial_misfit = sum_of_squares(values, first, last, trial);
    if (!(trial_misfit < 0.98 * misfit)) break;
    // With the noise known, the new component must explain more than noise would.
    if (!variance.empty() && !(chi_square(values, first, last, components, variance) -
                                   chi_square(values, first, last, trial, variance) >
                               settings.min_chi2_gain))
      break;
    components = std::move(trial);
    misfit = trial_misfit;
  }
  return components;
}

// A component is significant when it is positive, its peak through the smoothing filter clears
// the level, it holds its share of the energy, and it stays on the signal.
bool significant(const GaussianComponent& g, double total_area, int first, int last,
                 const DecompositionSettings& settings) {
  const double peak = smoothed_peak(g, settings.smooth_sigma_bins);
  return g.amplitude > 0.0 && peak > settings.significance_level &&
         g.area() >= settings.min_area_fraction * total_area && g.center_bin >= first &&
         g.center_bin <= last && g.sigma_bins >= 0.5 * settings.min_sigma_bins &&
         g.sigma_bins < (last - first + 1);
}

// Components that are not significant go, and the rest are fitted again without them, until
// all that are left are significant. When none passes on its own (a noisy return the components
// shared out between them), the signal is still there: it is described by the one Gaussian of
// its highest smoothed bin.
std::vector<GaussianComponent> drop_insignificant(std::span<const double> values,
                                                  std::span<const double> smoothed, int first,
                                                  int last,
                                                  std::vector<GaussianComponent> components,
                                                  const DecompositionSettings& settings) {
  for (int round = 0; round < settings.max_components && !components.empty(); ++round) {
    double total_area = 0.0;
    for (const GaussianComponent& g : components) total_area += std::max(g.area(), 0.0);
    std::vector<GaussianComponent> kept;
    for (const GaussianComponent& g : components)
      if (significant(g, total_area, first, last, settings)) kept.push_back(g);
    if (kept.size() == components.size()) break;
    if (kept.empty()) {
      const int peak =
          static_cast<int>(std::max_element(smoothed.begin() + first, smoothed.begin() + last + 1) -
                           smoothed.begin());
      std::vector<GaussianComponent> single =
          fit_gaussians(values, first, last, {peak_guess(smoothed, peak, first, last, settings)});
      components.clear();
      if (!single.empty() && single.front().amplitude > 0.0 &&
          std::isfinite(single.front().sigma_bins) && single.front().center_bin >= first &&
          single.front().center_bin <= last)
        components = std::move(single);
      break;
    }
    components = fit_gaussians(values, first, last, kept);
  }
  return components;
}

// With the noise known, the guesses (strongest first) join one at a time, each kept only when
// the fit with it lowers chi^2 by more than min_chi2_gain: a bump of noise on a broad return
// never becomes a component, and the fits stay as small as the signal needs.
std::vector<GaussianComponent> select_guesses(std::span<const double> values, int first, int last,
                                              const std::vector<GaussianComponent>& guesses,
                                              const DecompositionSettings& settings) {
  const std::span<const double> variance = settings.error_variance;
  std::vector<GaussianComponent> components = fit_gaussians(values, first, last, {guesses[0]});
  double misfit = chi_square(values, first, last, components, variance);
  std::vector<double> residual;  // over first..last, of the components; empty: to compute
  for (std::size_t k = 1; k < guesses.size(); ++k) {
    if (residual.empty()) residual = residual_over(values, first, last, components);
    if (linear_gain(residual, first, first, last, guesses[k], variance) <
        0.5 * settings.min_chi2_gain)
      continue;  // not worth a fit
    std::vector<GaussianComponent> trial = components;
    trial.push_back(guesses[k]);
    trial = fit_gaussians(values, first, last, trial);
    const double trial_misfit = chi_square(values, first, last, trial, variance);
    if (misfit - trial_misfit > settings.min_chi2_gain) {
      components = std::move(trial);
      misfit = trial_misfit;
      residual.clear();  // of the model before
    }
  }
  return components;
}

}  // namespace

std::vector<GaussianComponent> decompose_waveform(std::span<const double> values, int first,
                                                  int last, const DecompositionSettings& settings) {
  const int n = static_cast<int>(values.size());
  first = std::max(first, 0);
  last = std::min(last, n - 1);
  if (last - first < 2 || settings.max_components < 1) return {};
  DecompositionSettings capped = settings;
  capped.max_components = std::min(settings.max_components, kMaxFitComponents);
  if (capped.error_variance.size() != values.size() ||
      !(*std::max_element(capped.error_variance.begin() + first,
                          capped.error_variance.begin() + last + 1) > 0.0))
    capped.error_variance = {};  // no noise known (or none): no test
  const std::vector<double> smoothed = gaussian_smooth(values, capped.smooth_sigma_bins);
  std::vector<GaussianComponent> components = curvature_guesses(smoothed, first, last, capped);
  if (components.empty()) {
    // A return cut by the window's edge may not bend down inside it: its highest bin.
    const int peak = static_cast<int>(
        std::max_element(smoothed.begin() + first, smoothed.begin() + last + 1) - smoothed.begin());
    if (!(smoothed[peak] > capped.significance_level)) return {};
    components.push_back(peak_guess(smoothed, peak, first, last, capped));
  }
  components = capped.error_variance.empty()
                   ? fit_gaussians(values, first, last, components)
                   : select_guesses(values, first, last, components, capped);
  components = add_residual_components(values, first, last, std::move(components), capped);
  components = drop_insignificant(values, smoothed, first, last, std::move(components), capped);
  std::sort(components.begin(), components.end(),
            [](const GaussianComponent& a, const GaussianComponent& b) {
              return a.center_bin < b.center_bin;
            });
  return components;
}

}  // namespace glaswave
