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

  // The Earth's heliocentric and barycentric position and velocity (AU, AU/day): the sun's
  // place below and the observer's motion in eraApco, from one call (eraEpv00 is most of the
  // sun's cost, and eraAtco13 would evaluate it a second time for the same date).
  double heliocentric[2][3], barycentric[2][3];
  eraEpv00(tt1, tt2, heliocentric, barycentric);
  // The sun's barycentric position: the Earth's barycentric less its heliocentric (AU).
  double sun[3];
  for (int i = 0; i < 3; ++i) sun[i] = barycentric[0][i] - heliocentric[0][i];
  const double distance_au = eraPm(sun);
  double ra = 0, dec = 0;
  eraC2s(sun, &ra, &dec);
  // Its parallax (arcsec) for ERFA's space motion: the sun seen from the observer, not from the
  // barycentre (eraPmpx moves an object of any distance exactly, as a vector difference).
  const double parallax_arcsec = ERFA_DR2AS / distance_au;

  // eraAtco13's steps (eraApco13 then eraAtciq and eraAtioq, ERFA 2.0), with the Earth's
  // ephemeris above: the same calls on the same arguments, so the same bits. UT1 = UTC, no
  // polar motion, no refraction (pressure 0).
  double ut11 = 0, ut12 = 0;
  if (eraUtcut1(utc1, utc2, 0.0, &ut11, &ut12) < 0)
    throw std::invalid_argument("solar_position: ERFA cannot convert the time");
  double bpn[3][3];
  eraPnm06a(tt1, tt2, bpn);
  double cip_x = 0, cip_y = 0;
  eraBpn2xy(bpn, &cip_x, &cip_y);
  const double cio_s = eraS06(tt1, tt2, cip_x, cip_y);
  const double era = eraEra00(ut11, ut12);
  const double tio_s = eraSp00(tt1, tt2);
  double refa = 0, refb = 0;
  eraRefco(0.0, 0.0, 0.0, 0.0, &refa, &refb);
  eraASTROM astrom;
  eraApco(tt1, tt2, barycentric, heliocentric[0], cip_x, cip_y, cio_s, era, lon_deg * kDeg,
          lat_deg * kDeg, height_m, 0.0, 0.0, tio_s, refa, refb, &astrom);
  double ri = 0, di = 0;
  eraAtciq(ra, dec, 0.0, 0.0, parallax_arcsec, 0.0, &astrom, &ri, &di);
  double azimuth = 0, zenith = 0, hour_angle = 0, declination = 0, right_ascension = 0;
  eraAtioq(ri, di, &astrom, &azimuth, &zenith, &hour_angle, &declination, &right_ascension);
  SolarPosition position;
  position.elevation_deg = 90.0 - zenith / kDeg;
  position.azimuth_deg = std::fmod(azimuth / kDeg + 360.0, 360.0);
  return position;
}

}  // namespace glaswave
