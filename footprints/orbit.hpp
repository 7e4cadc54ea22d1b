// A Keplerian orbit with the secular J2 drift of its node, perigee and mean anomaly, and the
// Earth's rotation (GMST) that takes it from the inertial frame to the Earth-fixed one.
#pragma once

#include "footprints/track_settings.hpp"
#include "terrain/local_frame.hpp"

namespace glaswave {

// Greenwich mean sidereal time (rad, in [0, 2 pi)) at a time in seconds since the GLAS epoch,
// 2000-01-01T12:00:00Z, by the IAU 1982 formula (Vallado, "Fundamentals of Astrodynamics",
// eq. 3-47), with UT1 taken as UTC (they differ by under 0.9 s: under 420 m at the equator).
double gmst_rad(double time_s);

// Keplerian elements propagated with the J2 secular rates (Vallado eq. 9-41):
//   dΩ/dt = -3/2 n J2 (R/p)^2 cos i
//   dω/dt =  3/4 n J2 (R/p)^2 (5 cos^2 i - 1)
//   dM/dt =  n + 3/4 n J2 (R/p)^2 sqrt(1 - e^2) (3 cos^2 i - 1)
// with n = sqrt(GM/a^3), p = a (1 - e^2), R, GM and J2 of WGS84. The elements are taken as mean
// elements in the true-equator, mean-equinox frame of date (TEME, the frame of two-line
// elements), which GMST alone turns into the Earth-fixed frame; polar motion (~10 m) and the
// periodic J2 terms (km scale, not secular) are left out.
class Orbit {
 public:
  explicit Orbit(const OrbitElements& elements);

  // The elements at a time (seconds since the GLAS epoch); angles in degrees, in [0, 360).
  OrbitElements elements_at(double time_s) const;

  // Position (m) in the inertial frame (TEME) and in the Earth-fixed frame (WGS84 ECEF).
  Vec3 inertial_position_m(double time_s) const;
  Vec3 ecef_position_m(double time_s) const;

 private:
  OrbitElements epoch_;
  double raan_rate_rad_s_ = 0.0;
  double perigee_rate_rad_s_ = 0.0;
  double mean_anomaly_rate_rad_s_ = 0.0;
};

}  // namespace glaswave
