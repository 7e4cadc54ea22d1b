// Leaf angle distributions, the leaf scattering phase function, crown envelopes and stands,
// against closed forms and integrals done here independently.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <random>

#include "canopy/crown.hpp"
#include "canopy/leaf_angles.hpp"
#include "canopy/stand.hpp"

namespace glaswave {
namespace {

constexpr double pi = std::numbers::pi;

// de Wit's densities, written again here: g(theta_L) on [0, pi/2].
double de_wit(LeafAngleDistribution lad, double t) {
  switch (lad) {
    case LeafAngleDistribution::spherical:
      return std::sin(t);
    case LeafAngleDistribution::planophile:
      return 2 / pi * (1 + std::cos(2 * t));
    case LeafAngleDistribution::erectophile:
      return 2 / pi * (1 - std::cos(2 * t));
    case LeafAngleDistribution::plagiophile:
      return 2 / pi * (1 - std::cos(4 * t));
    case LeafAngleDistribution::extremophile:
      return 2 / pi * (1 + std::cos(4 * t));
    default:
      return 2 / pi;
  }
}

const LeafAngleDistribution all_de_wit[] = {
    LeafAngleDistribution::spherical,    LeafAngleDistribution::planophile,
    LeafAngleDistribution::erectophile,  LeafAngleDistribution::plagiophile,
    LeafAngleDistribution::extremophile, LeafAngleDistribution::uniform};

// G(mu) by Monte Carlo over leaf normals: inclination by rejection from g, azimuth uniform.
double projection_by_monte_carlo(LeafAngleDistribution lad, double mu, std::mt19937_64& engine) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double s = std::sqrt(1 - mu * mu);
  double sum = 0;
  const int n = 400000;
  for (int i = 0; i < n; ++i) {
    double t;
    do t = 0.5 * pi * u(engine);
    while (u(engine) * 1.3 > de_wit(lad, t));
    const double phi = 2 * pi * u(engine);
    sum += std::abs(mu * std::cos(t) + s * std::sin(t) * std::cos(phi));
  }
  return sum / n;
}

TEST(LeafAngles, ProjectionMatchesClosedFormsAndIntegrals) {
  const LeafAngles spherical(LeafAngleDistribution::spherical, 0);
  for (double mu : {0.0, 0.2, 0.5, 0.9, 1.0})
    EXPECT_NEAR(spherical.projection(mu), 0.5, 2e-4) << mu;
  // At nadir G = E[cos theta_L]: 8 / (3 pi), 4 / (3 pi), 2 / pi.
  EXPECT_NEAR(LeafAngles(LeafAngleDistribution::planophile, 0).projection(1.0), 8 / (3 * pi), 1e-3);
  EXPECT_NEAR(LeafAngles(LeafAngleDistribution::erectophile, 0).projection(1.0), 4 / (3 * pi),
              1e-3);
  EXPECT_NEAR(LeafAngles(LeafAngleDistribution::uniform, 0).projection(1.0), 2 / pi, 1e-3);
  std::mt19937_64 engine(42);
  for (LeafAngleDistribution lad : all_de_wit) {
    const LeafAngles angles(lad, 0);
    for (double mu : {0.1, 0.6}) {
      EXPECT_NEAR(angles.projection(mu) / projection_by_monte_carlo(lad, mu, engine), 1.0, 0.01)
          << static_cast<int>(lad) << " mu " << mu;
    }
    // The hemispherical mean of G is 1/2 for every distribution (Ross).
    double mean = 0;
    const int steps = 2000;
    for (int i = 0; i < steps; ++i) mean += angles.projection((i + 0.5) / steps) / steps;
    EXPECT_NEAR(mean, 0.5, 2e-3) << static_cast<int>(lad);
  }
  // Campbell's ellipsoidal distribution with a 57.3 degree mean is nearly spherical.
  const LeafAngles campbell(LeafAngleDistribution::ellipsoidal, 57.3);
  EXPECT_NEAR(campbell.projection(0.3), 0.5, 0.02);
}

// PHYSICS.md section 3: for spherical leaves Gamma(beta) = (rho + tau)/(3 pi)(sin b - b cos b)
// + (tau / 3) cos b with cos b = Omega' . Omega (so rho / 3 in exact backscatter), and
// (1/pi) integral of Gamma over all directions = omega G.
TEST(LeafAngles, SphericalPhaseFunctionAndItsIntegral) {
  const LeafAngles spherical(LeafAngleDistribution::spherical, 0);
  const double rho = 0.45, tau = 0.35;
  std::mt19937_64 engine(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  auto uniform = [&] { return u(engine); };
  const Vec3 incoming = normalized(Vec3{0.3, -0.2, -0.93});
  for (double beta_deg : {180.0, 120.0, 60.0}) {
    // Outgoing at angle beta from the incoming direction (beta = 180: straight back).
    const double b = beta_deg * pi / 180;
    const Vec3 side = normalized(cross(incoming, Vec3{0, 0, 1}));
    const Vec3 outgoing = std::cos(b) * incoming + std::sin(b) * side;
    double sum = 0;
    const int n = 400000;
    for (int i = 0; i < n; ++i) {
      const Vec3 normal = spherical.sample_normal(outgoing, uniform);
      sum += bilambertian_response(normal, incoming, outgoing, rho, tau);
    }
    // The estimator gives Gamma / G, G = 1/2; beta is the angle between the travel directions.
    const double cos_beta = dot(incoming, outgoing);
    const double beta = std::acos(cos_beta);
    const double gamma =
        (rho + tau) / (3 * pi) * (std::sin(beta) - beta * cos_beta) + tau / 3 * cos_beta;
    EXPECT_NEAR(0.5 * sum / n / gamma, 1.0, 0.01) << beta_deg;
  }
  // (1/pi) integral of Gamma(Omega' -> Omega) dOmega = omega G(Omega'), for a non-spherical LAD.
  const LeafAngles planophile(LeafAngleDistribution::planophile, 0);
  double sum = 0;
  const int n = 400000;
  for (int i = 0; i < n; ++i) {
    const Vec3 normal = planophile.sample_normal(incoming, uniform);
    const double z = 2 * u(engine) - 1, phi = 2 * pi * u(engine), r = std::sqrt(1 - z * z);
    const Vec3 outgoing{r * std::cos(phi), r * std::sin(phi), z};
    sum += bilambertian_response(normal, outgoing, incoming, rho, tau);  // f |n . Omega|
  }
  const double integral = planophile.projection(incoming[2]) * 4 * pi * sum / n / pi;
  EXPECT_NEAR(integral / ((rho + tau) * planophile.projection(incoming[2])), 1.0, 0.01);
}

TEST(Crown, IntervalsOfEllipsoidsAndCones) {
  Crown ellipsoid{CrownShape::ellipsoid, {10, 20, 15}, 8, 8, 0.1};
  auto down = crown_interval(ellipsoid, {10, 20, 100}, {0, 0, -1});
  ASSERT_TRUE(down);
  EXPECT_NEAR(down->first, 100 - 31, 1e-9);
  EXPECT_NEAR(down->second, 100 - 15, 1e-9);
  // From inside, the entry lies behind the origin.
  auto inside = crown_interval(ellipsoid, {10, 20, 23}, {1, 0, 0});
  ASSERT_TRUE(inside);
  EXPECT_NEAR(inside->first, -8, 1e-9);
  EXPECT_NEAR(inside->second, 8, 1e-9);
  EXPECT_FALSE(crown_interval(ellipsoid, {19, 20, 100}, {0, 0, -1}));

  Crown cone{CrownShape::cone, {0, 0, 10}, 4, 5, 0.1};  // 10 m tall, apex at 20 m
  // A vertical line 1 m off the axis: inside from the base up to 20 - 10 * 1/4 = 17.5 m.
  auto vertical = crown_interval(cone, {1, 0, 50}, {0, 0, -1});
  ASSERT_TRUE(vertical);
  EXPECT_NEAR(50 - vertical->second, 10, 1e-9);
  EXPECT_NEAR(50 - vertical->first, 17.5, 1e-9);
  // A horizontal line at 15 m: the radius there is 4 * (20 - 15) / 10 = 2 m.
  auto across = crown_interval(cone, {-10, 0, 15}, {1, 0, 0});
  ASSERT_TRUE(across);
  EXPECT_NEAR(across->first, 8, 1e-9);
  EXPECT_NEAR(across->second, 12, 1e-9);
  EXPECT_FALSE(crown_interval(cone, {-10, 0, 21}, {1, 0, 0}));
  EXPECT_NEAR(crown_volume_m3(CrownShape::cone, 4, 5), pi * 16 * 10 / 3, 1e-9);
}

TEST(Stand, TreesStayPutAndGiveTheCoverAndPai) {
  CanopySettings canopy;  // Table 1: cover 0.7, radius 8 m, PAI 3
  const Stand stand(canopy, 11);
  const auto near = stand.trees_near(45.0, 7.0, 300.0);
  const auto shifted = stand.trees_near(45.001, 7.001, 300.0);
  // Trees seen from both queries are the same trees.
  std::map<std::pair<double, double>, double> first;
  for (const Tree& t : near) first[{t.lat_deg, t.lon_deg}] = t.crown_base_m;
  int shared = 0;
  for (const Tree& t : shifted) {
    auto found = first.find({t.lat_deg, t.lon_deg});
    if (found != first.end()) {
      ++shared;
      EXPECT_EQ(found->second, t.crown_base_m);
      EXPECT_GE(t.crown_base_m, 15.0);
      EXPECT_LE(t.crown_base_m, 20.0);
    }
  }
  EXPECT_GT(shared, 100);
  // Cover: the part of a 200 m square under some crown (metres from degrees at 45 N).
  const double m_lat = 111132.954 - 559.822 * std::cos(2 * 45 * pi / 180),
               m_lon = 111412.84 * std::cos(45 * pi / 180);
  std::mt19937_64 engine(3);
  std::uniform_real_distribution<double> u(-100.0, 100.0);
  int covered = 0;
  const int samples = 20000;
  for (int i = 0; i < samples; ++i) {
    const double x = u(engine), y = u(engine);
    for (const Tree& t : near) {
      const double dx = (t.lon_deg - 7.0) * m_lon - x, dy = (t.lat_deg - 45.0) * m_lat - y;
      if (dx * dx + dy * dy <= 64.0) {
        ++covered;
        break;
      }
    }
  }
  EXPECT_NEAR(static_cast<double>(covered) / samples, 0.7, 0.05);
  // PAI: the plant area of the trees standing in the 200 m square (their crowns' volume times
  // the density), per square metre; Poisson counts of ~760 trees: within 4 / sqrt(760) = 15 %.
  int stems = 0;
  for (const Tree& t : near)
    if (std::abs((t.lon_deg - 7.0) * m_lon) < 100.0 && std::abs((t.lat_deg - 45.0) * m_lat) < 100.0)
      ++stems;
  const double pai =
      stems * (4.0 / 3.0 * pi * 64.0 * 8.0) * stand.area_density_m2_m3() / (200.0 * 200.0);
  EXPECT_NEAR(pai / 3.0, 1.0, 4.0 / std::sqrt(stems));
}

// Small crowns at high cover: many trees a tile (here ~1000), counted without underflow.
TEST(Stand, SmallCrownsKeepTheirDensity) {
  CanopySettings canopy;
  canopy.crown_radius_m = 0.5;
  canopy.cover = 0.7;
  const Stand stand(canopy, 4);
  const double expected_per_m2 = -std::log(1.0 - 0.7) / (pi * 0.25);
  EXPECT_NEAR(stand.trees_per_m2(), expected_per_m2, 1e-12);
  const double m_lat = 111132.954 - 559.822 * std::cos(2 * 45 * pi / 180),
               m_lon = 111412.84 * std::cos(45 * pi / 180);
  int stems = 0;
  for (const Tree& t : stand.trees_near(45.0, 7.0, 30.0))
    if (std::abs((t.lon_deg - 7.0) * m_lon) < 20.0 && std::abs((t.lat_deg - 45.0) * m_lat) < 20.0)
      ++stems;
  const double expected = expected_per_m2 * 40.0 * 40.0;
  EXPECT_NEAR(stems, expected, 4.0 * std::sqrt(expected));
}

}  // namespace
}  // namespace glaswave
