// The sun's elevation and azimuth from the Astronomical Almanac's low-precision formulas.
#include "footprints/sun_position.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace glaswave {
namespace {

constexpr double degree = std::numbers::pi / 180.0;

}  // namespace

SunPosition sun_position(double seconds_since_glas_epoch, double lat_deg, double lon_deg) {
  const double n = seconds_since_glas_epoch / 86400.0;
  const double mean_longitude = 280.460 + 0.9856474 * n;
  const double g = (357.528 + 0.9856003 * n) * degree;
  const double ecliptic =
      (mean_longitude + 1.915 * std::sin(g) + 0.020 * std::sin(2.0 * g)) * degree;
  const double obliquity = (23.439 - 4e-7 * n) * degree;
  const double right_ascension =
      std::atan2(std::cos(obliquity) * std::sin(ecliptic), std::cos(ecliptic));
  const double declination = std::asin(std::sin(obliquity) * std::sin(ecliptic));
  const double sidereal_deg = std::fmod(15.0 * (18.697374558 + 24.06570982441908 * n), 360.0);
  const double hour_angle = (sidereal_deg + lon_deg) * degree - right_ascension;
  const double lat = lat_deg * degree;
  const double sin_elevation = std::sin(lat) * std::sin(declination) +
                               std::cos(lat) * std::cos(declination) * std::cos(hour_angle);
  SunPosition sun;
  sun.elevation_deg = std::asin(std::clamp(sin_elevation, -1.0, 1.0)) / degree;
  const double azimuth =
      std::atan2(-std::sin(hour_angle) * std::cos(declination),
                 std::sin(declination) * std::cos(lat) -
                     std::sin(lat) * std::cos(declination) * std::cos(hour_angle));
  sun.azimuth_deg = std::fmod(azimuth / degree + 360.0, 360.0);
  return sun;
}

}  // namespace glaswave
