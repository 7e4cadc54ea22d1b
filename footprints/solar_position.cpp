// The sun's elevation and azimuth through ERFA.
#include "footprints/solar_position.hpp"

#include <erfa.h>
#include <erfam.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace glaswave {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
// GLAS epoch 2000-01-01T12:00:00 as a Julian date.
constexpr double kGlasEpochJd = 2451545.0;
// The years ERFA's ephemeris of the Earth (eraEpv00) is meant for, as seconds from the epoch.
constexpr double kEarliestS = -100.0 * 365.25 * 86400.0;
constexpr double kLatestS = 100.0 * 365.25 * 86400.0;

}  // namespace

SolarPosition solar_position(double time_s, double lat_deg, double lon_deg, double height_m) {
  if (!std::isfinite(time_s) || !std::isfinite(lat_deg) || !std::isfinite(lon_deg) ||
      !std::isfinite(height_m))
    throw std::invalid_argument("solar_position: a time or position that is not finite");
  if (time_s < kEarliestS || time_s > kLatestS)
    throw std::invalid_argument("solar_position: a time outside the years 1900-2100");

  // The time stamp counts days of 86400 s: its day and fraction are a UTC quasi-Julian date.
  const double days = time_s / 86400.0;
  const double utc1 = kGlasEpochJd + std::floor(days);
  const double utc2 = days - std::floor(days);
  double tai1 = 0, tai2 = 0, tt1 = 0, tt2 = 0;
  // A status of 1 ("dubious year": beyond the leap-second table) still converts.
  if (eraUtctai(utc1, utc2, &tai1, &tai2) < 0 || eraTaitt(tai1, tai2, &tt1, &tt2) != 0)
    throw std::invalid_argument("solar_position: ERFA cannot convert the time");

  // The sun's barycentric position: the Earth's barycentric less its heliocentric (AU).
  double heliocentric[2][3], barycentric[2][3];
  eraEpv00(tt1, tt2, heliocentric, barycentric);
  double sun[3];
  for (int i = 0; i < 3; ++i) sun[i] = barycentric[0][i] - heliocentric[0][i];
  const double distance_au = eraPm(sun);
  double ra = 0, dec = 0;
  eraC2s(sun, &ra, &dec);
  // Its parallax (arcsec) for ERFA's space motion: the sun seen from the observer, not from the
  // barycentre (eraPmpx moves an object of any distance exactly, as a vector difference).
  const double parallax_arcsec = ERFA_DR2AS / distance_au;

  double azimuth = 0, zenith = 0, hour_angle = 0, declination = 0, right_ascension = 0, eo = 0;
  const int status = eraAtco13(ra, dec, 0.0, 0.0, parallax_arcsec, 0.0, utc1, utc2, 0.0,
                               lon_deg * kDeg, lat_deg * kDeg, height_m, 0.0, 0.0,
                               /*phpa: no refraction*/ 0.0, 0.0, 0.0, 0.0, &azimuth, &zenith,
                               &hour_angle, &declination, &right_ascension, &eo);
  if (status < 0) throw std::invalid_argument("solar_position: ERFA cannot convert the time");
  SolarPosition position;
  position.elevation_deg = 90.0 - zenith / kDeg;
  position.azimuth_deg = std::fmod(azimuth / kDeg + 360.0, 360.0);
  return position;
}

}  // namespace glaswave
