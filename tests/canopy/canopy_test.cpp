// Leaf angle distributions, the leaf scattering phase function, crown envelopes and stands,
// against closed forms and integrals done here independently.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <vector>

#include "canopy/crown.hpp"
#include "canopy/leaf_angles.hpp"
#include "canopy/stand.hpp"

namespace glaswave {
namespace {

constexpr double pi = std::numbers::pi;

// Moments of de Wit's inclination densities (de Wit 1965; Goel and Strebel 1984), integrated by
// hand: g = 2/pi (1 +- cos 2t) or 2/pi (1 +- cos 4t) on [0, pi/2], sin t for spherical leaves,
// 2/pi for uniform ones; E[cos t], E[sin t] and E[cos^2 t].
struct Moments {
  LeafAngleDistribution lad;
  double cos, sin, cos_sq;
};
const Moments de_wit_moments[] = {
    {LeafAngleDistribution::spherical, 1 / 2.0, pi / 4, 1 / 3.0},
    {LeafAngleDistribution::planophile, 8 / (3 * pi), 4 / (3 * pi), 3 / 4.0},
    {LeafAngleDistribution::erectophile, 4 / (3 * pi), 8 / (3 * pi), 1 / 4.0},
    {LeafAngleDistribution::plagiophile, 32 / (15 * pi), 32 / (15 * pi), 1 / 2.0},
    {LeafAngleDistribution::extremophile, 28 / (15 * pi), 28 / (15 * pi), 1 / 2.0},
    {LeafAngleDistribution::uniform, 2 / pi, 2 / pi, 1 / 2.0}};

// G at the vertical is E[cos t]; at the horizon, where a leaf of inclination t presents
// sin t |cos phi| on average over azimuths phi, it is (2/pi) E[sin t] (Ross 1981). The
// hemispherical mean of G is 1/2 for every distribution (Ross). The tables behind G are
// integrated to well under 1e-3.
TEST(LeafAngles, ProjectionMatchesClosedForms) {
  for (const Moments& m : de_wit_moments) {
    SCOPED_TRACE(static_cast<int>(m.lad));
    const LeafAngles angles(m.lad, 0);
    EXPECT_NEAR(angles.projection(1.0), m.cos, 1e-3);
    EXPECT_NEAR(angles.projection(0.0), 2 / pi * m.sin, 1e-3);
    double mean = 0;
    const int steps = 2000;
    for (int i = 0; i < steps; ++i) mean += angles.projection((i + 0.5) / steps) / steps;
    EXPECT_NEAR(mean, 0.5, 2e-3);
  }
  const LeafAngles spherical(LeafAngleDistribution::spherical, 0);
  for (double mu : {0.2, 0.5, 0.9}) EXPECT_NEAR(spherical.projection(mu), 0.5, 2e-4) << mu;
  // Campbell's ellipsoidal distribution with a 57.3 degree mean is nearly spherical.
  const LeafAngles campbell(LeafAngleDistribution::ellipsoidal, 57.3);
  EXPECT_NEAR(campbell.projection(0.3), 0.5, 0.02);
}

// Normals met by a vertical ray are drawn from g(t) |cos t| / G(1), so their mean cosine is
// E[cos^2 t] / E[cos t]; within 4 standard errors of the sample mean.
TEST(LeafAngles, NormalsMetByAVerticalRayFollowTheWeightedDensity) {
  std::mt19937_64 engine(42);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  auto uniform = [&] { return u(engine); };
  const int n = 100000;
  for (const Moments& m : de_wit_moments) {
    SCOPED_TRACE(static_cast<int>(m.lad));
    const LeafAngles angles(m.lad, 0);
    double sum = 0, sum_sq = 0;
    for (int i = 0; i < n; ++i) {
      const double c = angles.sample_normal({0, 0, -1}, uniform)[2];
      sum += c;
      sum_sq += c * c;
    }
    const double mean = sum / n, sd = std::sqrt(sum_sq / n - mean * mean);
    EXPECT_NEAR(mean, m.cos_sq / m.cos, 4 * sd / std::sqrt(n));
  }
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

// The standard deviation of the covered fraction of a window of `area_m2` under a Boolean
// model of discs (radius r, intensity lambda = -ln(1 - cover) / (pi r^2)), estimated from
// `samples` random points. Two points s apart are both uncovered with probability
// q^2 exp(lambda gamma(s)), gamma the area the two discs about them share (Chiu et al.,
// "Stochastic Geometry and its Applications", 3.1); integrating the covariance over the plane
// gives the window's variance (edge effects only lower it), and the points add binomial noise.
double boolean_cover_sd(double cover, double r, double area_m2, int samples) {
  const double q = 1 - cover, lambda = -std::log(q) / (pi * r * r);
  double integral = 0;
  const int steps = 4000;
  for (int i = 0; i < steps; ++i) {
    const double s = (i + 0.5) * 2 * r / steps;
    const double shared =
        2 * r * r * std::acos(s / (2 * r)) - 0.5 * s * std::sqrt(4 * r * r - s * s);
    integral += (std::exp(lambda * shared) - 1) * 2 * pi * s * (2 * r / steps);
  }
  return std::sqrt(q * q * integral / area_m2 + cover * q / samples);
}

// The part of a square (half-width `half_m`, centred on 45 N 7 E) under some crown, at random
// points.
double covered_fraction(const std::vector<Tree>& trees, double half_m, double r, int samples) {
  const double m_lat = 111132.954 - 559.822 * std::cos(2 * 45 * pi / 180),
               m_lon = 111412.84 * std::cos(45 * pi / 180);
  std::mt19937_64 engine(3);
  std::uniform_real_distribution<double> u(-half_m, half_m);
  int covered = 0;
  for (int i = 0; i < samples; ++i) {
    const double x = u(engine), y = u(engine);
    for (const Tree& t : trees) {
      const double dx = (t.lon_deg - 7.0) * m_lon - x, dy = (t.lat_deg - 45.0) * m_lat - y;
      if (dx * dx + dy * dy <= r * r) {
        ++covered;
        break;
      }
    }
  }
  return static_cast<double>(covered) / samples;
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
  // Cover: the part of a 1 km square under some crown, within 4 standard deviations of the
  // Boolean model's (0.0063 here: 0.0054 from the trees' places, 0.0032 from the points).
  const int samples = 20000;
  EXPECT_NEAR(covered_fraction(stand.trees_near(45.0, 7.0, 720.0), 500.0, 8.0, samples), 0.7,
              4 * boolean_cover_sd(0.7, 8.0, 1000.0 * 1000.0, samples));
  // PAI: the plant area of the trees standing in the 200 m square (their crowns' volume times
  // the density), per square metre; Poisson counts of ~760 trees: within 4 / sqrt(760) = 15 %.
  const double m_lat = 111132.954 - 559.822 * std::cos(2 * 45 * pi / 180),
               m_lon = 111412.84 * std::cos(45 * pi / 180);
  int stems = 0;
  for (const Tree& t : near)
    if (std::abs((t.lon_deg - 7.0) * m_lon) < 100.0 && std::abs((t.lat_deg - 45.0) * m_lat) < 100.0)
      ++stems;
  const double pai =
      stems * (4.0 / 3.0 * pi * 64.0 * 8.0) * stand.area_density_m2_m3() / (200.0 * 200.0);
  EXPECT_NEAR(pai / 3.0, 1.0, 4.0 / std::sqrt(stems));
  // Another kind of canopy in the same run grows other trees.
  const auto other = Stand(canopy, 11, 1).trees_near(45.0, 7.0, 300.0);
  int same = 0;
  for (const Tree& t : other) same += first.count({t.lat_deg, t.lon_deg});
  EXPECT_EQ(same, 0);
}

// Small crowns at high cover: many trees a tile (here ~1000), drawn without underflow. Stems in
// a 40 m square against the Boolean model's density -ln(1 - cover) / (pi r^2), within 4 Poisson
// standard deviations; the cover they give within 4 of its standard deviations.
TEST(Stand, SmallCrownsKeepTheirDensityAndCover) {
  CanopySettings canopy;
  canopy.crown_radius_m = 0.5;
  canopy.cover = 0.7;
  const Stand stand(canopy, 4);
  const double m_lat = 111132.954 - 559.822 * std::cos(2 * 45 * pi / 180),
               m_lon = 111412.84 * std::cos(45 * pi / 180);
  const std::vector<Tree> trees = stand.trees_near(45.0, 7.0, 30.0);
  int stems = 0;
  for (const Tree& t : trees)
    if (std::abs((t.lon_deg - 7.0) * m_lon) < 20.0 && std::abs((t.lat_deg - 45.0) * m_lat) < 20.0)
      ++stems;
  const double expected = -std::log(1.0 - 0.7) / (pi * 0.25) * 40.0 * 40.0;
  EXPECT_NEAR(stems, expected, 4.0 * std::sqrt(expected));
  const int samples = 20000;  // standard deviation 0.0091: 0.0085 from the trees, 0.0032 points
  EXPECT_NEAR(covered_fraction(trees, 20.0, 0.5, samples), 0.7,
              4 * boolean_cover_sd(0.7, 0.5, 40.0 * 40.0, samples));
}

}  // namespace
}  // namespace glaswave
