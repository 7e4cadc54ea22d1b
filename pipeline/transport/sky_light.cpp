// The sky's light for the photon-counting background, traced through the layers.
#include "pipeline/transport/sky_light.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <span>

#include "core/random.hpp"
#include "pipeline/transport/atmosphere.hpp"

namespace glaswave {

constexpr int sun_nodes = 20;

double SkyLight::reflectance(double mu, double rho) const {
  if (!(mu > 0.0) || mu_sun.empty()) return 0.0;
  const double x = std::clamp(mu, mu_sun.front(), mu_sun.back());
  const auto upper = std::lower_bound(mu_sun.begin(), mu_sun.end(), x);
  const std::size_t j = std::max<std::size_t>(1, upper - mu_sun.begin());
  const double t = (x - mu_sun[j - 1]) / (mu_sun[j] - mu_sun[j - 1]);
  auto at = [&](const std::vector<double>& v) { return v[j - 1] + t * (v[j] - v[j - 1]); };
  return at(path_reflectance) +
         rho * at(down_transmission) * up_transmission / (1.0 - rho * spherical_albedo);
}

SkyLight sky_light(const AtmosphereSettings& settings, std::size_t bands, std::size_t band,
                   std::uint64_t seed, int photons) {
  const AtmosphereModel layers(settings, bands, 0.0, 0.0, 0.0);
  constexpr double inf = std::numeric_limits<double>::infinity();
  const Vec3 nadir_view{0.0, 0.0, 1.0};  // toward the receiver
  std::vector<double> weight(bands);
  double path_sum = 0.0;
  // Each scattering's light toward the receiver above: pi p(Theta) exp(-tau above) (mu_v = 1).
  const AtmosphereModel::ScatterSeen seen = [&](const Vec3& point, const Vec3& arriving,
                                                const AtmospherePhase& phase,
                                                std::span<const double> w) {
    path_sum += w[band] * std::numbers::pi * phase_function(phase, dot(arriving, nadir_view)) *
                std::exp(-layers.optical_depth(band, point[2], inf));
  };
  SkyLight sky;
  for (int node = 0; node <= sun_nodes; ++node) {
    const bool from_below = node == sun_nodes;  // S: the scene's Lambertian light going up
    const double mu0 = from_below ? 1.0 : (node + 1.0) / sun_nodes;
    path_sum = 0.0;
    double arrived = 0.0;
    for (int p = 0; p < photons; ++p) {
      RandomStream random(seed, node, p, RandomPurpose::sky);
      const std::function<double()> uniform = [&random] { return random.uniform(); };
      std::fill(weight.begin(), weight.end(), 1.0);
      Vec3 position{0.0, 0.0, layers.top_z_m()}, direction{0.0, 0.0, -1.0};
      if (from_below) {  // cosine-weighted upward
        const double mu = std::sqrt(uniform()), phi = 2.0 * std::numbers::pi * uniform();
        const double s = std::sqrt(1.0 - mu * mu);
        position = {0.0, 0.0, layers.floor_z_m()};
        direction = {s * std::cos(phi), s * std::sin(phi), mu};
      } else {
        direction = {std::sqrt(1.0 - mu0 * mu0), 0.0, -mu0};
      }
      double path_m = 0.0;
      const bool down = layers.cross(position, direction, path_m, weight, uniform, nullptr, &seen);
      // Down at the floor (with no layer, the upward light has simply left).
      if (down && direction[2] < 0.0) arrived += weight[band];
    }
    if (from_below) {
      sky.spherical_albedo = arrived / photons;
      break;
    }
    sky.mu_sun.push_back(mu0);
    sky.path_reflectance.push_back(path_sum / photons);
    sky.down_transmission.push_back(arrived / photons);
  }
  sky.up_transmission = sky.down_transmission.back();
  return sky;
}

}  // namespace glaswave
