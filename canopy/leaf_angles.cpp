// Leaf angle distributions: de Wit's classes, uniform, and Campbell's ellipsoidal.
#include "canopy/leaf_angles.hpp"

#include <algorithm>
#include <numbers>

namespace glaswave {
namespace {

constexpr double pi = std::numbers::pi;
constexpr int inclination_steps = 2048;
constexpr int projection_steps = 128;

}  // namespace

LeafAngles::LeafAngles(LeafAngleDistribution distribution, double mean_deg)
    : distribution_(distribution) {
  if (distribution == LeafAngleDistribution::ellipsoidal) {
    // Campbell (1990): the ellipsoid's axis ratio from the mean leaf inclination in radians,
    // inverting mean = 9.65 (3 + chi)^-1.65.
    campbell_chi_ = -3.0 + std::pow(mean_deg * pi / 180.0 / 9.65, -0.6061);
  }
  // Cumulative distribution of the inclination by the midpoint rule, normalised numerically so
  // that every distribution integrates to exactly one.
  inclination_cdf_.assign(inclination_steps + 1, 0.0);
  const double step = 0.5 * pi / inclination_steps;
  for (int i = 0; i < inclination_steps; ++i)
    inclination_cdf_[i + 1] = inclination_cdf_[i] + density(step * (i + 0.5)) * step;
  const double total = inclination_cdf_.back();
  for (double& value : inclination_cdf_) value /= total;

  // G(mu) = integral of g(theta_L) psi(mu, theta_L), with psi the leaf's projection averaged
  // over leaf azimuths: (1/2pi) * integral |cos t cos tL + sin t sin tL cos phi| dphi.
  projection_table_.assign(projection_steps + 1, 0.0);
  constexpr int azimuth_steps = 128;
  for (int m = 0; m <= projection_steps; ++m) {
    const double mu = static_cast<double>(m) / projection_steps;
    const double sin_zenith = std::sqrt(std::max(0.0, 1.0 - mu * mu));
    double g_sum = 0.0;
    for (int i = 0; i < inclination_steps / 8; ++i) {
      const double leaf_step = 0.5 * pi / (inclination_steps / 8);
      const double inclination = leaf_step * (i + 0.5);
      double psi = 0.0;
      for (int k = 0; k < azimuth_steps; ++k) {
        const double phi = 2.0 * pi * (k + 0.5) / azimuth_steps;
        psi += std::abs(mu * std::cos(inclination) +
                        sin_zenith * std::sin(inclination) * std::cos(phi));
      }
      g_sum += density(inclination) / total * (psi / azimuth_steps) * leaf_step;
    }
    projection_table_[m] = g_sum;
  }
}

double LeafAngles::density(double t) const {
  switch (distribution_) {
    case LeafAngleDistribution::spherical:
      return std::sin(t);
    case LeafAngleDistribution::planophile:
      return 2.0 / pi * (1.0 + std::cos(2.0 * t));
    case LeafAngleDistribution::erectophile:
      return 2.0 / pi * (1.0 - std::cos(2.0 * t));
    case LeafAngleDistribution::plagiophile:
      return 2.0 / pi * (1.0 - std::cos(4.0 * t));
    case LeafAngleDistribution::extremophile:
      return 2.0 / pi * (1.0 + std::cos(4.0 * t));
    case LeafAngleDistribution::uniform:
      return 2.0 / pi;
    case LeafAngleDistribution::ellipsoidal: {
      const double chi = campbell_chi_;
      const double d = chi + 1.774 * std::pow(chi + 1.182, -0.733);
      const double c = std::cos(t), s = std::sin(t);
      return 2.0 * chi * chi * chi * s / (d * std::pow(c * c + chi * chi * s * s, 2.0));
    }
  }
  return 0.0;
}

double LeafAngles::projection(double cos_zenith) const {
  const double position = std::min(std::abs(cos_zenith), 1.0) * projection_steps;
  const int i = std::min(static_cast<int>(position), projection_steps - 1);
  const double f = position - i;
  return (1.0 - f) * projection_table_[i] + f * projection_table_[i + 1];
}

Vec3 LeafAngles::normal_at(double u_inclination, double u_azimuth) const {
  // Invert the tabulated cumulative distribution, linearly within a step.
  const auto upper =
      std::upper_bound(inclination_cdf_.begin(), inclination_cdf_.end(), u_inclination);
  const int i =
      std::clamp(static_cast<int>(upper - inclination_cdf_.begin()) - 1, 0, inclination_steps - 1);
  const double width = inclination_cdf_[i + 1] - inclination_cdf_[i];
  const double f = width > 0.0 ? (u_inclination - inclination_cdf_[i]) / width : 0.5;
  const double inclination = (i + f) * 0.5 * pi / inclination_steps;
  const double azimuth = 2.0 * pi * u_azimuth;
  return {std::sin(inclination) * std::cos(azimuth), std::sin(inclination) * std::sin(azimuth),
          std::cos(inclination)};
}

}  // namespace glaswave
