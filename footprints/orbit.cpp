// Keplerian orbit with J2 secular rates; sidereal time.
#include "footprints/orbit.hpp"

#include <GeographicLib/Constants.hpp>
#include <GeographicLib/NormalGravity.hpp>
#include <cmath>
#include <numbers>

namespace glaswave {
namespace {

constexpr double deg = std::numbers::pi / 180.0;
constexpr double two_pi = 2.0 * std::numbers::pi;

double wrapped_deg(double angle_deg) {
  const double wrapped = std::fmod(angle_deg, 360.0);
  return wrapped < 0.0 ? wrapped + 360.0 : wrapped;
}

// Eccentric anomaly from the mean anomaly (rad), Newton's method on Kepler's equation.
double eccentric_anomaly(double mean_anomaly_rad, double eccentricity) {
  const double m = std::remainder(mean_anomaly_rad, two_pi);
  double e_anomaly = eccentricity < 0.8 ? m : std::numbers::pi;
  for (int iteration = 0; iteration < 50; ++iteration) {
    const double step = (e_anomaly - eccentricity * std::sin(e_anomaly) - m) /
                        (1.0 - eccentricity * std::cos(e_anomaly));
    e_anomaly -= step;
    if (std::abs(step) < 1e-15) break;
  }
  return e_anomaly;
}

}  // namespace

double gmst_rad(double time_s) {
  // Julian centuries of UT1 from J2000 (JD 2451545.0 is the GLAS epoch itself).
  const double t = time_s / (86400.0 * 36525.0);
  // In seconds of time. The formula's (876600 h) T term is exactly one sidereal second per
  // second of time, written as time_s so that it keeps its precision over decades.
  const double gmst_s = 67310.54841 + time_s + (8640184.812866 + (0.093104 - 6.2e-6 * t) * t) * t;
  const double turns = std::fmod(gmst_s / 86400.0, 1.0);
  return (turns < 0.0 ? turns + 1.0 : turns) * two_pi;
}

Orbit::Orbit(const OrbitElements& elements) : epoch_(elements) {
  const double gm_m3_s2 = GeographicLib::Constants::WGS84_GM();
  const double radius_m = GeographicLib::Constants::WGS84_a();
  const double j2 = GeographicLib::NormalGravity::WGS84().DynamicalFormFactor(2);
  const double a = elements.semi_major_axis_m, e = elements.eccentricity;
  const double p = a * (1.0 - e * e);
  const double cos_i = std::cos(elements.inclination_deg * deg);
  const double mean_motion_rad_s = std::sqrt(gm_m3_s2 / (a * a * a));
  const double k = mean_motion_rad_s * j2 * (radius_m / p) * (radius_m / p);
  raan_rate_rad_s_ = -1.5 * k * cos_i;
  perigee_rate_rad_s_ = 0.75 * k * (5.0 * cos_i * cos_i - 1.0);
  mean_anomaly_rate_rad_s_ =
      mean_motion_rad_s + 0.75 * k * std::sqrt(1.0 - e * e) * (3.0 * cos_i * cos_i - 1.0);
}

OrbitElements Orbit::elements_at(double time_s) const {
  const double dt_s = time_s - epoch_.epoch_s;
  OrbitElements now = epoch_;
  now.epoch_s = time_s;
  now.raan_deg = wrapped_deg(epoch_.raan_deg + raan_rate_rad_s_ * dt_s / deg);
  now.arg_perigee_deg = wrapped_deg(epoch_.arg_perigee_deg + perigee_rate_rad_s_ * dt_s / deg);
  now.mean_anomaly_deg =
      wrapped_deg(epoch_.mean_anomaly_deg + mean_anomaly_rate_rad_s_ * dt_s / deg);
  return now;
}

Vec3 Orbit::inertial_position_m(double time_s) const {
  const OrbitElements now = elements_at(time_s);
  const double e = now.eccentricity;
  const double e_anomaly = eccentric_anomaly(now.mean_anomaly_deg * deg, e);
  const double radius_m = now.semi_major_axis_m * (1.0 - e * std::cos(e_anomaly));
  const double true_anomaly =
      std::atan2(std::sqrt(1.0 - e * e) * std::sin(e_anomaly), std::cos(e_anomaly) - e);
  // Perifocal -> inertial: rotations by the argument of latitude, the inclination and the node.
  const double u = now.arg_perigee_deg * deg + true_anomaly;
  const double node = now.raan_deg * deg, inclination = now.inclination_deg * deg;
  const double cos_u = std::cos(u), sin_u = std::sin(u);
  const double cos_node = std::cos(node), sin_node = std::sin(node);
  const double cos_i = std::cos(inclination), sin_i = std::sin(inclination);
  return {radius_m * (cos_node * cos_u - sin_node * sin_u * cos_i),
          radius_m * (sin_node * cos_u + cos_node * sin_u * cos_i), radius_m * sin_u * sin_i};
}

Vec3 Orbit::ecef_position_m(double time_s) const {
  const Vec3 inertial = inertial_position_m(time_s);
  const double theta = gmst_rad(time_s);
  const double c = std::cos(theta), s = std::sin(theta);
  return {c * inertial[0] + s * inertial[1], -s * inertial[0] + c * inertial[1], inertial[2]};
}

}  // namespace glaswave
