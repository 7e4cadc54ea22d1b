// The one normal and the one Poisson sampler, over any source of uniforms in [0, 1) with a
// `uniform()` member (RandomStream): the detector's noise, the stands' tree counts and the
// roughness's white noise all draw through these.
#pragma once

#include <math.h>  // lgamma_r

#include <cmath>
#include <numbers>

namespace glaswave {

// A standard normal deviate by Box-Muller, from two uniforms; 1 - u keeps the logarithm finite.
template <typename Random>
double standard_normal(Random& random) {
  const double radius = std::sqrt(-2.0 * std::log(1.0 - random.uniform()));
  return radius * std::cos(2.0 * std::numbers::pi * random.uniform());
}

// An exact Poisson deviate (a whole number, as a double): multiplication of uniforms for small
// means, Hörmann's PTRS (transformed rejection with squeeze, as NumPy uses it) for means of 10
// and more, so that the cost does not grow with the mean. 0 for a mean that is not positive.
template <typename Random>
double poisson(Random& random, double mean) {
  if (!(mean > 0.0)) return 0.0;
  if (mean < 10.0) {
    double product = random.uniform();
    // 0 when the first uniform is at most exp(-mean) (which is above 1 - 2 mean by more than a
    // rounding): most draws of a small mean end here, without the exponential, to the same bit.
    if (product <= 1.0 - 2.0 * mean) return 0.0;
    const double limit = std::exp(-mean);
    double k = 0.0;
    while (product > limit) {
      product *= random.uniform();
      k += 1.0;
    }
    return k;
  }
  const double slam = std::sqrt(mean), loglam = std::log(mean);
  const double b = 0.931 + 2.53 * slam;
  const double a = -0.059 + 0.02483 * b;
  const double invalpha = 1.1239 + 1.1328 / (b - 3.4);
  const double vr = 0.9277 - 3.6224 / (b - 2.0);
  for (;;) {
    const double u = random.uniform() - 0.5;
    const double v = random.uniform();
    const double us = 0.5 - std::abs(u);
    const double k = std::floor((2.0 * a / us + b) * u + mean + 0.43);
    if (us >= 0.07 && v <= vr) return k;
    if (k < 0.0 || (us < 0.013 && v > us)) continue;
    // lgamma_r: std::lgamma writes the global signgam, a data race between threads (found by
    // ThreadSanitizer, tests/threads); the same value.
    int sign = 0;
    if (std::log(v) + std::log(invalpha) - std::log(a / (us * us) + b) <=
        -mean + k * loglam - ::lgamma_r(k + 1.0, &sign))
      return k;
  }
}

}  // namespace glaswave
