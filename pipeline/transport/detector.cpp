// The detector chain, bin by bin, each bin with its own counter-based random stream.
#include "pipeline/transport/detector.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/random.hpp"
#include "core/samplers.hpp"

namespace glaswave {
namespace {

constexpr double planck_J_s = 6.62607015e-34;
constexpr double light_m_s = 299792458.0;
constexpr std::size_t max_bands = std::size_t{1} << 8;
constexpr std::size_t max_bins = std::size_t{1} << 24;

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
    RandomStream random(seed_, static_cast<std::uint64_t>(shot), (band << 24) | bin,
                        RandomPurpose::detector);
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
