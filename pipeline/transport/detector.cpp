// The detector chain, bin by bin, each bin with its own counter-based random stream.
#include "pipeline/transport/detector.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "core/random.hpp"

namespace glaswave {
namespace {

constexpr double planck_J_s = 6.62607015e-34;
constexpr double light_m_s = 299792458.0;
// Keeps the detector's streams apart from the transport's, which use (seed, shot, ray) too.
constexpr std::uint64_t detector_stream = 0xd37ec70b5eed5a17ULL;
constexpr std::size_t max_bands = std::size_t{1} << 8;
constexpr std::size_t max_bins = std::size_t{1} << 24;

double standard_normal(RayRandom& random) {
  // Box-Muller; 1 - u keeps the logarithm finite.
  const double radius = std::sqrt(-2.0 * std::log(1.0 - random.uniform()));
  return radius * std::cos(2.0 * std::numbers::pi * random.uniform());
}

// Exact Poisson deviates: multiplication of uniforms for small means, Hörmann's PTRS
// (transformed rejection, as NumPy uses it) for large ones.
double poisson(RayRandom& random, double mean) {
  if (!(mean > 0.0)) return 0.0;
  if (mean < 10.0) {
    const double limit = std::exp(-mean);
    double product = random.uniform();
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
    if (std::log(v) + std::log(invalpha) - std::log(a / (us * us) + b) <=
        -mean + k * loglam - std::lgamma(k + 1.0))
      return k;
  }
}

}  // namespace

Detector::Detector(const Settings& settings, std::uint64_t seed)
    : settings_(settings), seed_(seed) {}

std::vector<double> Detector::record(std::span<const double> power_W, double bin_ns,
                                     double wavelength_nm, std::int64_t shot,
                                     std::size_t band) const {
  if (band >= max_bands || power_W.size() > max_bins)
    throw std::invalid_argument("detector: at most 256 bands and 2^24 bins");
  const Settings& s = settings_;
  const double photon_J = planck_J_s * light_m_s / (wavelength_nm * 1e-9);
  const double bin_s = bin_ns * 1e-9;
  const double levels = s.bits > 0 ? std::ldexp(1.0, s.bits) - 1.0 : 0.0;
  const double lsb = s.bits > 0 ? *s.saturation_W / levels : 0.0;
  std::vector<double> out(power_W.size());
  for (std::size_t bin = 0; bin < power_W.size(); ++bin) {
    // One stream per (seed, shot, band, bin): a bin's noise depends on nothing else.
    RayRandom random(seed_ ^ detector_stream, static_cast<std::uint64_t>(shot), (band << 24) | bin);
    double x = power_W[bin] + s.background_W;
    if (s.photon_noise) {
      const double electrons =
          poisson(random, s.quantum_efficiency * std::max(x, 0.0) * bin_s / photon_J);
      x = electrons / s.quantum_efficiency * photon_J / bin_s;
    }
    if (s.noise_rms_W > 0.0) x += s.noise_rms_W * standard_normal(random);
    double v = s.gain * x;
    if (s.saturation_W) v = std::min(v, *s.saturation_W);
    if (s.bits > 0) v = std::clamp(std::round(v / lsb), 0.0, levels) * lsb;
    out[bin] = v / s.gain;
  }
  return out;
}

}  // namespace glaswave
