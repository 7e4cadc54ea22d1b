// Gaussian decomposition through GSL's trust-region least squares (multifit_nlinear, Levenberg-
// Marquardt steps with Moré scaling), with analytic Jacobians.
#include "pipeline/products/gaussian_decomposition.hpp"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_multifit_nlinear.h>
#include <gsl/gsl_vector.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <mutex>
#include <numbers>

namespace glaswave {
namespace {

// GSL's default error handler aborts the process; library code must return instead. Its
// handler is a process-wide setting, made once.
void silence_gsl() {
  static std::once_flag once;
  std::call_once(once, [] { gsl_set_error_handler_off(); });
}

struct WorkspaceFree {
  void operator()(gsl_multifit_nlinear_workspace* w) const { gsl_multifit_nlinear_free(w); }
};
struct VectorFree {
  void operator()(gsl_vector* v) const { gsl_vector_free(v); }
};

// What the GSL callbacks see: the data (scaled to order 1) over the fitted bins.
struct FitData {
  std::span<const double> y;  // scaled values of the fitted bins
  int first = 0;              // bin index of y[0]
};

// Beyond this many sigma a Gaussian is below 1e-14 of its peak: taken as 0, which spares most
// of the exponentials of a narrow component over a long waveform.
constexpr double kCutoffSigmas = 8.0;

// Parameters per component: amplitude, centre and width, all free. (A width held above the
// pulse's through sigma^2 = min^2 + w^2 has a zero derivative where a flat surface's return sits,
// at the pulse's width, and the fit then crawls there for hundreds of iterations.)

int residuals(const gsl_vector* x, void* params, gsl_vector* f) {
  const auto& data = *static_cast<const FitData*>(params);
  const std::size_t components = x->size / 3;
  for (std::size_t i = 0; i < data.y.size(); ++i) {
    const double t = data.first + static_cast<double>(i);
    double model = 0.0;
    for (std::size_t k = 0; k < components; ++k) {
      const double a = gsl_vector_get(x, 3 * k), c = gsl_vector_get(x, 3 * k + 1);
      const double s = gsl_vector_get(x, 3 * k + 2);
      const double u = (t - c) / s;
      if (std::abs(u) < kCutoffSigmas) model += a * std::exp(-0.5 * u * u);
    }
    gsl_vector_set(f, i, model - data.y[i]);
  }
  return GSL_SUCCESS;
}

int jacobian(const gsl_vector* x, void* params, gsl_matrix* J) {
  const auto& data = *static_cast<const FitData*>(params);
  const std::size_t components = x->size / 3;
  for (std::size_t i = 0; i < data.y.size(); ++i) {
    const double t = data.first + static_cast<double>(i);
    for (std::size_t k = 0; k < components; ++k) {
      const double a = gsl_vector_get(x, 3 * k), c = gsl_vector_get(x, 3 * k + 1);
      const double s = gsl_vector_get(x, 3 * k + 2);
      const double d = t - c;
      const double e =
          std::abs(d) < kCutoffSigmas * std::abs(s) ? std::exp(-0.5 * d * d / (s * s)) : 0.0;
      gsl_matrix_set(J, i, 3 * k, e);
      gsl_matrix_set(J, i, 3 * k + 1, a * e * d / (s * s));
      gsl_matrix_set(J, i, 3 * k + 2, a * e * d * d / (s * s * s));
    }
  }
  return GSL_SUCCESS;
}

double model_at(const std::vector<GaussianComponent>& components, double x) {
  double sum = 0.0;
  for (const GaussianComponent& g : components) sum += g.value_at(x);
  return sum;
}

double sum_of_squares(std::span<const double> values, int first, int last,
                      const std::vector<GaussianComponent>& components) {
  double sum = 0.0;
  for (int i = first; i <= last; ++i) {
    const double r = values[i] - model_at(components, i);
    sum += r * r;
  }
  return sum;
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

// A first guess for a peak at bin `peak` of the smoothed waveform: the width seen through the
// filter with the filter taken out, never below the pulse.
GaussianComponent guess(std::span<const double> values, std::span<const double> smoothed, int peak,
                        int first, int last, const DecompositionSettings& settings) {
  const double seen = half_width(smoothed, peak, first, last) / std::sqrt(2.0 * std::numbers::ln2);
  const double filter = settings.smooth_sigma_bins;
  const double sigma = std::sqrt(std::max(seen * seen - filter * filter,
                                          1.2 * settings.min_sigma_bins * settings.min_sigma_bins));
  // The filter lowers a peak by sigma / sqrt(sigma^2 + filter^2): undo that on the smoothed value,
  // which is steadier under noise than the raw bin.
  const double amplitude =
      std::max(values[peak], smoothed[peak] * std::sqrt(sigma * sigma + filter * filter) / sigma);
  return {amplitude, static_cast<double>(peak), sigma};
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
  std::vector<double> out(n);
  for (int i = 0; i < n; ++i) {
    double sum = 0.0, weight = 0.0;
    for (int k = std::max(-half, -i); k <= std::min(half, n - 1 - i); ++k) {
      sum += kernel[k + half] * values[i + k];
      weight += kernel[k + half];
    }
    out[i] = sum / weight;
  }
  return out;
}

std::vector<GaussianComponent> fit_gaussians(std::span<const double> values, int first, int last,
                                             const std::vector<GaussianComponent>& initial) {
  silence_gsl();
  const std::size_t n = static_cast<std::size_t>(last - first + 1);
  const std::size_t p = 3 * initial.size();
  if (initial.empty() || n < p || first < 0 || last >= static_cast<int>(values.size()))
    return initial;

  // Scaled to order 1, so that the tolerances mean the same for any power level.
  double scale = 0.0;
  for (int i = first; i <= last; ++i) scale = std::max(scale, std::abs(values[i]));
  if (!(scale > 0.0) || !std::isfinite(scale)) return initial;
  std::vector<double> y(n);
  for (std::size_t i = 0; i < n; ++i) y[i] = values[first + i] / scale;
  FitData data{y, first};

  std::unique_ptr<gsl_vector, VectorFree> x(gsl_vector_alloc(p));
  for (std::size_t k = 0; k < initial.size(); ++k) {
    const GaussianComponent& g = initial[k];
    gsl_vector_set(x.get(), 3 * k, g.amplitude / scale);
    gsl_vector_set(x.get(), 3 * k + 1, g.center_bin);
    gsl_vector_set(x.get(), 3 * k + 2, g.sigma_bins);
  }

  gsl_multifit_nlinear_fdf fdf{};
  fdf.f = residuals;
  fdf.df = jacobian;
  fdf.fvv = nullptr;
  fdf.n = n;
  fdf.p = p;
  fdf.params = &data;
  gsl_multifit_nlinear_parameters parameters = gsl_multifit_nlinear_default_parameters();
  parameters.scale = gsl_multifit_nlinear_scale_more;
  // Normal equations by Cholesky: a few times faster than the default QR on a few hundred bins,
  // and accurate enough with the data scaled to order 1.
  parameters.solver = gsl_multifit_nlinear_solver_cholesky;
  std::unique_ptr<gsl_multifit_nlinear_workspace, WorkspaceFree> workspace(
      gsl_multifit_nlinear_alloc(gsl_multifit_nlinear_trust, &parameters, n, p));
  if (!workspace || gsl_multifit_nlinear_init(x.get(), &fdf, workspace.get()) != GSL_SUCCESS)
    return initial;
  int info = 0;
  // Not converging within the iterations (GSL_EMAXITER) or making no more progress
  // (GSL_ENOPROG) still leaves the best point found, which is what is wanted. A step below
  // 1e-7 of a parameter is far finer than a waveform resolves (1e-5 bin on a centre).
  gsl_multifit_nlinear_driver(100, 1e-7, 1e-7, 0.0, nullptr, nullptr, &info, workspace.get());
  const gsl_vector* solution = gsl_multifit_nlinear_position(workspace.get());

  std::vector<GaussianComponent> fitted;
  for (std::size_t k = 0; k < initial.size(); ++k) {
    GaussianComponent g{gsl_vector_get(solution, 3 * k) * scale,
                        gsl_vector_get(solution, 3 * k + 1),
                        std::abs(gsl_vector_get(solution, 3 * k + 2))};
    if (!std::isfinite(g.amplitude) || !std::isfinite(g.center_bin) || !std::isfinite(g.sigma_bins))
      return initial;
    fitted.push_back(g);
  }
  return fitted;
}

namespace {

// Initial guesses: the local maxima of the smoothed waveform above the level, strongest first,
// at most max_components. A monotonic signal (cut by the window's edge) gives its highest bin;
// none above the level gives none.
std::vector<int> initial_peaks(std::span<const double> smoothed, int first, int last,
                               const DecompositionSettings& settings) {
  const int n = static_cast<int>(smoothed.size());
  const double level = settings.significance_level;
  std::vector<int> peaks;
  for (int i = std::max(first, 1); i <= std::min(last, n - 2); ++i) {
    if (smoothed[i] > level && smoothed[i] > smoothed[i - 1] && smoothed[i] >= smoothed[i + 1])
      peaks.push_back(i);
  }
  if (peaks.empty()) {
    int best = first;
    for (int i = first; i <= last; ++i)
      if (smoothed[i] > smoothed[best]) best = i;
    if (!(smoothed[best] > level)) return {};
    peaks.push_back(best);
  }
  std::sort(peaks.begin(), peaks.end(), [&](int a, int b) { return smoothed[a] > smoothed[b]; });
  if (static_cast<int>(peaks.size()) > settings.max_components)
    peaks.resize(settings.max_components);
  return peaks;
}

// Signal the fit leaves in the residual (a peak hidden in its neighbour's flank, most often)
// gets a component of its own, as long as it makes the fit better.
std::vector<GaussianComponent> add_residual_components(std::span<const double> values, int first,
                                                       int last,
                                                       std::vector<GaussianComponent> components,
                                                       const DecompositionSettings& settings) {
  const int n = static_cast<int>(values.size());
  double misfit = sum_of_squares(values, first, last, components);
  std::vector<double> residual(n, 0.0);
  while (static_cast<int>(components.size()) < settings.max_components) {
    for (int i = 0; i < n; ++i) residual[i] = values[i] - model_at(components, i);
    const std::vector<double> smooth_residual =
        gaussian_smooth(residual, settings.smooth_sigma_bins);
    int best = first;
    for (int i = first; i <= last; ++i)
      if (smooth_residual[i] > smooth_residual[best]) best = i;
    if (!(smooth_residual[best] > settings.significance_level)) break;
    std::vector<GaussianComponent> trial = components;
    trial.push_back(guess(residual, smooth_residual, best, first, last, settings));
    trial = fit_gaussians(values, first, last, trial);
    const double trial_misfit = sum_of_squares(values, first, last, trial);
    if (!(trial_misfit < 0.98 * misfit)) break;
    components = std::move(trial);
    misfit = trial_misfit;
  }
  return components;
}

// A component is significant when it is positive, its peak through the smoothing filter clears
// the level, it holds its share of the energy, and it stays on the signal.
bool significant(const GaussianComponent& g, double total_area, int first, int last,
                 const DecompositionSettings& settings) {
  return g.amplitude > 0.0 &&
         smoothed_peak(g, settings.smooth_sigma_bins) > settings.significance_level &&
         g.area() >= settings.min_area_fraction * total_area && g.center_bin >= first &&
         g.center_bin <= last && g.sigma_bins >= 0.5 * settings.min_sigma_bins &&
         g.sigma_bins < (last - first + 1);
}

// Components that are not significant go, and the rest are fitted again without them, until
// all that are left are significant. When none passes on its own (a noisy return the components
// shared out between them), the signal is still there: it is described by the one Gaussian of
// its strongest peak.
std::vector<GaussianComponent> drop_insignificant(std::span<const double> values,
                                                  std::span<const double> smoothed, int first,
                                                  int last, int strongest_peak,
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
      std::vector<GaussianComponent> single = fit_gaussians(
          values, first, last, {guess(values, smoothed, strongest_peak, first, last, settings)});
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

}  // namespace

std::vector<GaussianComponent> decompose_waveform(std::span<const double> values, int first,
                                                  int last, const DecompositionSettings& settings) {
  const int n = static_cast<int>(values.size());
  first = std::max(first, 0);
  last = std::min(last, n - 1);
  if (last - first < 2 || settings.max_components < 1) return {};
  const std::vector<double> smoothed = gaussian_smooth(values, settings.smooth_sigma_bins);
  const std::vector<int> peaks = initial_peaks(smoothed, first, last, settings);
  if (peaks.empty()) return {};
  std::vector<GaussianComponent> components;
  for (int peak : peaks) components.push_back(guess(values, smoothed, peak, first, last, settings));
  components = fit_gaussians(values, first, last, components);
  components = add_residual_components(values, first, last, std::move(components), settings);
  components = drop_insignificant(values, smoothed, first, last, peaks.front(),
                                  std::move(components), settings);
  std::sort(components.begin(), components.end(),
            [](const GaussianComponent& a, const GaussianComponent& b) {
              return a.center_bin < b.center_bin;
            });
  return components;
}

}  // namespace glaswave
