// Leaf angle distributions: de Wit's classes, uniform, and Campbell's ellipsoidal.
#include "canopy/leaf_angles.hpp"

#include <algorithm>
#include <array>
#include <numbers>

namespace glaswave {
namespace {

constexpr double pi = std::numbers::pi;
constexpr int inclination_steps = 2048;
constexpr int projection_steps = 128;
constexpr int guide_steps = 1024;  // a power of two

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
  constexpr int leaf_steps = inclination_steps / 8;
  const double leaf_step = 0.5 * pi / leaf_steps;
  // The cosines and the density at the quadrature's nodes, once (the same values each time).
  std::array<double, azimuth_steps> cos_phi;
  for (int k = 0; k < azimuth_steps; ++k)
    cos_phi[k] = std::cos(2.0 * pi * (k + 0.5) / azimuth_steps);
  std::array<double, leaf_steps> cos_leaf, sin_leaf, weight;
  for (int i = 0; i < leaf_steps; ++i) {
    const double inclination = leaf_step * (i + 0.5);
    cos_leaf[i] = std::cos(inclination);
    sin_leaf[i] = std::sin(inclination);
    weight[i] = density(inclination) / total;
  }
  for (int m = 0; m <= projection_steps; ++m) {
    const double mu = static_cast<double>(m) / projection_steps;
    const double sin_zenith = std::sqrt(std::max(0.0, 1.0 - mu * mu));
    double g_sum = 0.0;
    for (int i = 0; i < leaf_steps; ++i) {
      double psi = 0.0;
      for (int k = 0; k < azimuth_steps; ++k)
        psi += std::abs(mu * cos_leaf[i] + sin_zenith * sin_leaf[i] * cos_phi[k]);
      g_sum += weight[i] * (psi / azimuth_steps) * leaf_step;
    }
    projection_table_[m] = g_sum;
  }
  inclination_nodes_.resize(inclination_steps + 1);
  for (int i = 0; i <= inclination_steps; ++i)
    inclination_nodes_[i] = {std::sin(step * i), std::cos(step * i)};
  // Where each 1 / guide_steps of the cumulative distribution starts, for normal_at's search.
  inclination_guide_.resize(guide_steps + 1);
  for (int j = 0; j <= guide_steps; ++j)
    inclination_guide_[j] =
        static_cast<int>(std::upper_bound(inclination_cdf_.begin(), inclination_cdf_.end(),
                                          static_cast<double>(j) / guide_steps) -
                         inclination_cdf_.begin());
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
  // Invert the tabulated cumulative distribution, linearly within a step. The first value above
  // u lies between the guide's entries about u (u * guide_steps is exact: a power of two).
  const int g = std::clamp(static_cast<int>(u_inclination * guide_steps), 0, guide_steps - 1);
  const auto upper =
      std::upper_bound(inclination_cdf_.begin() + inclination_guide_[g],
                       inclination_cdf_.begin() + inclination_guide_[g + 1], u_inclination);
  const int i =
      std::clamp(static_cast<int>(upper - inclination_cdf_.begin()) - 1, 0, inclination_steps - 1);
  const double width = inclination_cdf_[i + 1] - inclination_cdf_[i];
  const double f = width > 0.0 ? (u_inclination - inclination_cdf_[i]) / width : 0.5;
  // The inclination (i + f) step, its sine and cosine from the node's (no libm call).
  const SinCos inclination =
      rotate_small(inclination_nodes_[i], f * (0.5 * pi / inclination_steps));
  const SinCos azimuth = sincos_turn(u_azimuth);
  return {inclination.sin * azimuth.cos, inclination.sin * azimuth.sin, inclination.cos};
}

}  // namespace glaswave
