// Orbit propagation: the node drifts at the J2 rate, the nodal period and the westward shift of
// the ground track follow from the J2 rates and the Earth's rotation, radii stay on the ellipse,
// and sidereal time matches a published value. Expected values are computed here from the
// formulas, with constants typed in, not read from the code under test.
#include "footprints/orbit.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/glas_time.hpp"

namespace glaswave {
namespace {

constexpr double pi = std::numbers::pi;
constexpr double deg = pi / 180.0;
constexpr double gm_m3_s2 = 3.986004418e14;  // WGS84
constexpr double radius_m = 6378137.0;       // WGS84 a
constexpr double j2 = 1.08262668e-3;         // EGM96 (WGS84 normal gravity has 1.0826300e-3)
constexpr double earth_rate_rad_s = 7.2921158553e-5;  // sidereal, IAU 1982 GMST rate

OrbitElements icesat() {
  OrbitElements o;
  o.semi_major_axis_m = radius_m + 600000.0;
  o.eccentricity = 0.0;
  o.inclination_deg = 94.0;
  o.raan_deg = 40.0;
  o.arg_perigee_deg = 0.0;
  o.mean_anomaly_deg = 0.0;
  o.epoch_s = parse_iso8601_utc("2005-10-21T12:00:00Z");
  return o;
}

// Time (s) of the ascending equator crossing in [t0, t1], by bisection on z.
double ascending_node_time_s(const Orbit& orbit, double t0, double t1) {
  for (int i = 0; i < 200 && t1 - t0 > 1e-7; ++i) {
    const double mid = 0.5 * (t0 + t1);
    (orbit.inertial_position_m(mid)[2] < 0.0 ? t0 : t1) = mid;
  }
  return 0.5 * (t0 + t1);
}

// Right ascension of the ascending node measured from the orbit itself, where the spacecraft
// crosses the equator northward, at the first crossing after `after_s`.
struct Node {
  double time_s, raan_rad;
};
Node measured_node(const Orbit& orbit, double after_s) {
  double t = after_s;
  while (!(orbit.inertial_position_m(t)[2] < 0.0 && orbit.inertial_position_m(t + 10.0)[2] >= 0.0))
    t += 10.0;
  const double crossing_s = ascending_node_time_s(orbit, t, t + 10.0);
  const Vec3 node = orbit.inertial_position_m(crossing_s);
  return {crossing_s, std::atan2(node[1], node[0])};
}

TEST(Orbit, NodeDriftsAtTheJ2Rate) {
  const OrbitElements elements = icesat();
  const Orbit orbit(elements);
  const double a = elements.semi_major_axis_m;
  const double n = std::sqrt(gm_m3_s2 / (a * a * a));
  const double p = a * (1.0 - elements.eccentricity * elements.eccentricity);
  // dΩ/dt = -3/2 n J2 (R/p)^2 cos i (Vallado, Fundamentals of Astrodynamics, eq. 9-41).
  const double expected_rad_s =
      -1.5 * n * j2 * (radius_m / p) * (radius_m / p) * std::cos(94.0 * deg);
  const Node first = measured_node(orbit, elements.epoch_s + 60.0);
  const Node later = measured_node(orbit, elements.epoch_s + 10.0 * 86400.0);
  const double measured_rad_s =
      std::remainder(later.raan_rad - first.raan_rad, 2 * pi) / (later.time_s - first.time_s);
  // About +0.51 deg a day for ICESat (retrograde by 4 deg from polar: the node moves east).
  EXPECT_NEAR(measured_rad_s * 86400.0 / deg, 0.509, 0.005);
  // 1e-5 relative covers the two J2 values (3e-6 apart).
  EXPECT_NEAR(measured_rad_s / expected_rad_s, 1.0, 1e-5);
  // The node at the epoch is the one given.
  const Node at_epoch = measured_node(orbit, elements.epoch_s - 60.0);
  EXPECT_NEAR(at_epoch.time_s, elements.epoch_s, 1e-6);
  EXPECT_NEAR(std::remainder(at_epoch.raan_rad - 40.0 * deg, 2 * pi), 0.0, 1e-9);
}

TEST(Orbit, NodalPeriodAndGroundTrackShiftFollowFromJ2AndEarthRotation) {
  const OrbitElements elements = icesat();
  const Orbit orbit(elements);
  const double a = elements.semi_major_axis_m;
  const double n = std::sqrt(gm_m3_s2 / (a * a * a));
  const double k = 0.75 * n * j2 * (radius_m / a) * (radius_m / a);
  const double cos_i = std::cos(94.0 * deg);
  // The argument of latitude advances at dω/dt + dM/dt; for e = 0 a revolution from node to node
  // takes 2 pi / (n + k (5 cos^2 i - 1) + k (3 cos^2 i - 1)); Kepler alone would say 2 pi / n.
  const double nodal_period_s =
      2 * pi / (n + k * (5 * cos_i * cos_i - 1) + k * (3 * cos_i * cos_i - 1));
  const double keplerian_period_s = 2 * pi / n;
  const double first = ascending_node_time_s(orbit, elements.epoch_s - 100, elements.epoch_s + 100);
  const double second = ascending_node_time_s(orbit, first + keplerian_period_s - 100,
                                              first + keplerian_period_s + 100);
  EXPECT_NEAR(second - first, nodal_period_s, 1e-3);
  EXPECT_GT(std::abs(nodal_period_s - keplerian_period_s),
            5.0);  // so the check above tells J2 apart

  // Between two ascending nodes the Earth turns east under the orbit, whose node moves east too:
  // the ground track's node moves west by (earth rate - node rate) * period.
  const double node_rate = -2.0 * k * cos_i;
  const Vec3 at_first = orbit.ecef_position_m(first), at_second = orbit.ecef_position_m(second);
  const double shift_rad = std::remainder(
      std::atan2(at_second[1], at_second[0]) - std::atan2(at_first[1], at_first[0]), 2 * pi);
  EXPECT_NEAR(shift_rad, -(earth_rate_rad_s - node_rate) * (second - first), 1e-7);
  EXPECT_NEAR(shift_rad / deg, -24.2, 0.1);
}

TEST(Orbit, CircularOrbitKeepsItsRadiusAndAltitude) {
  const OrbitElements elements = icesat();
  const Orbit orbit(elements);
  double lowest_m = 1e12, highest_m = 0;
  for (double t = 0; t < 6000.0; t += 7.0) {
    const Vec3 p = orbit.ecef_position_m(elements.epoch_s + t);
    EXPECT_NEAR(norm(p), elements.semi_major_axis_m, 1e-3);
    const double altitude_m = geodetic_from_ecef(p).h_m;
    lowest_m = std::min(lowest_m, altitude_m);
    highest_m = std::max(highest_m, altitude_m);
  }
  // 600 km over the equator; over the poles the ellipsoid is 21.4 km lower (a - b).
  EXPECT_NEAR(lowest_m, 600000.0, 100.0);
  EXPECT_NEAR(highest_m, 600000.0 + 21384.7, 300.0);
}

TEST(Orbit, EccentricOrbitSpansPerigeeToApogee) {
  OrbitElements elements = icesat();
  elements.semi_major_axis_m = 7500000.0;
  elements.eccentricity = 0.1;
  elements.arg_perigee_deg = 75.0;
  elements.mean_anomaly_deg = 0.0;  // at perigee at the epoch
  const Orbit orbit(elements);
  const double period_s = 2 * pi * std::sqrt(std::pow(7500000.0, 3) / gm_m3_s2);
  double lowest_m = 1e12, highest_m = 0;
  for (double t = 0; t < period_s; t += 1.0) {
    const double r = norm(orbit.inertial_position_m(elements.epoch_s + t));
    lowest_m = std::min(lowest_m, r);
    highest_m = std::max(highest_m, r);
  }
  EXPECT_NEAR(norm(orbit.inertial_position_m(elements.epoch_s)), 7500000.0 * 0.9, 1e-3);
  EXPECT_NEAR(lowest_m, 7500000.0 * 0.9, 1.0);
  EXPECT_NEAR(highest_m, 7500000.0 * 1.1, 1.0);
  // Half a period after perigee the spacecraft is at apogee (the period is Keplerian to 1e-3).
  EXPECT_NEAR(norm(orbit.inertial_position_m(elements.epoch_s + period_s / 2)), 7500000.0 * 1.1,
              50.0);
}

TEST(Gmst, MatchesPublishedValues) {
  // Vallado, Fundamentals of Astrodynamics, example 3-5: 1992 August 20, 12:14 UT1.
  EXPECT_NEAR(gmst_rad(parse_iso8601_utc("1992-08-20T12:14:00Z")) / deg, 152.578787886, 1e-6);
  // At J2000.0 itself: 18h 41m 50.54841s (the formula's constant term).
  EXPECT_NEAR(gmst_rad(0.0) / deg, 280.46061837, 1e-7);
}

}  // namespace
}  // namespace glaswave
