// Decomposition of a waveform into a sum of Gaussians (Hofton et al. 2000, as GLA14 and GEDI
// L2A do): initial guesses from the inflection points and curvature of a smoothed waveform, a
// Levenberg-Marquardt fit of our own over the signal's window (analytic Jacobian, at most
// kMaxFitComponents Gaussians in fixed arrays, no allocation per iteration, an iteration cap),
// components added where the residual still holds signal and dropped when they are not
// significant (above a level and, where each bin's noise is known, by a chi^2 test). Works in
// bin units; the caller turns them into times and elevations.
#pragma once

#include <span>
#include <vector>

namespace glaswave {

// The most Gaussians one fit takes (its fixed arrays' size); max_components is capped at it.
constexpr int kMaxFitComponents = 6;

// One component: amplitude * exp(-(x - center)^2 / (2 sigma^2)), x the bin index.
struct GaussianComponent {
  double amplitude = 0.0;   // in the waveform's unit (W)
  double center_bin = 0.0;  // fractional bin index
  double sigma_bins = 0.0;

  // Integral over x, in waveform unit x bins.
  double area() const;
  double value_at(double x) const;
};

struct DecompositionSettings {
  int max_components = 6;  // GLA14 and GEDI keep up to 6
  // No return is narrower than the transmitted pulse: a component fitted narrower than half of
  // it is a spike of noise, not a return, and is dropped. (Guesses start no narrower than it.)
  double min_sigma_bins = 1.0;
  // Width of the Gaussian filter that finds the peaks (GLAS smooths with the pulse's own width).
  double smooth_sigma_bins = 1.0;
  // A component is kept only when its peak, seen through the smoothing filter, stands above
  // this level (the signal threshold above the noise), and it holds at least
  // min_area_fraction of the fitted energy.
  double significance_level = 0.0;
  double min_area_fraction = 0.005;
  // The noise of each bin of the values (W^2, indexed as they are), as the variance that an
  // independent error would need to weigh as much in a sum of squares (a noise correlated
  // over L bins counts L times its variance). Empty: unknown, and every component that clears
  // the level is kept. Given: a component is kept only when it lowers chi^2 (the squared
  // residuals over each bin's error variance, floored at a tenth of the window's largest) by
  // more than min_chi2_gain (a likelihood-ratio test of 3 more parameters).
  std::span<const double> error_variance;
  // chi^2 with 3 degrees of freedom exceeds 25 by chance with p = 1.6e-5: p = 0.001 for the
  // best of the ~60 places a pulse-wide component can take in a window of a few hundred bins.
  double min_chi2_gain = 25.0;
};

// A Gaussian filter of `sigma_bins` (truncated at 4 sigma, renormalised at the ends, so that a
// constant stays constant up to the edges).
std::vector<double> gaussian_smooth(std::span<const double> values, double sigma_bins);

// Least-squares fit of `initial.size()` Gaussians to values[first..last] (inclusive), from the
// initial guesses, every parameter free. Returns the fitted components, or the initial ones
// unchanged when the fit cannot start (more than kMaxFitComponents, fewer bins than parameters,
// nothing but zeros) or ends on a non-finite value. `values` has the noise level removed.
std::vector<GaussianComponent> fit_gaussians(std::span<const double> values, int first, int last,
                                             const std::vector<GaussianComponent>& initial);

// The decomposition of values[first..last] (the signal's extent, noise level removed), sorted
// by centre (waveform order: the first component is the earliest, the highest). Empty when
// nothing stands above the significance level.
std::vector<GaussianComponent> decompose_waveform(std::span<const double> values, int first,
                                                  int last, const DecompositionSettings& settings);

}  // namespace glaswave
