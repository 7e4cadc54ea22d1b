// The sun's elevation and azimuth through ERFA.
#include "footprints/solar_position.hpp"

#include <erfa.h>
#include <erfam.h>

#include <array>
#include <cmath>
#include <cstdint>
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

namespace {

void check_arguments(double time_s, double lat_deg, double lon_deg, double height_m) {
  if (!std::isfinite(time_s) || !std::isfinite(lat_deg) || !std::isfinite(lon_deg) ||
      !std::isfinite(height_m))
    throw std::invalid_argument("solar_position: a time or position that is not finite");
  if (time_s < kEarliestS || time_s > kLatestS)
    throw std::invalid_argument("solar_position: a time outside the years 1900-2100");
}

// The time stamp as UTC and TT two-part Julian dates.
struct Dates {
  double utc1 = 0, utc2 = 0, tt1 = 0, tt2 = 0;
};

Dates dates_of(double time_s) {
  // The time stamp counts days of 86400 s: its day and fraction are a UTC quasi-Julian date.
  const double days = time_s / 86400.0;
  Dates d;
  d.utc1 = kGlasEpochJd + std::floor(days);
  d.utc2 = days - std::floor(days);
  double tai1 = 0, tai2 = 0;
  // A status of 1 ("dubious year": beyond the leap-second table) still converts.
  if (eraUtctai(d.utc1, d.utc2, &tai1, &tai2) < 0 || eraTaitt(tai1, tai2, &d.tt1, &d.tt2) != 0)
    throw std::invalid_argument("solar_position: ERFA cannot convert the time");
  return d;
}

// What depends on TT alone: the Earth's heliocentric position and barycentric position and
// velocity (AU, AU/day), and the CIP's X, Y and the CIO locator s (rad).
struct TimeTerms {
  double heliocentric[3];
  double barycentric[2][3];
  double cip_x, cip_y, cio_s;
};

TimeTerms time_terms(const Dates& d) {
  TimeTerms terms{};
  // The Earth's heliocentric and barycentric position and velocity: the sun's place below and
  // the observer's motion in eraApco, from one call (eraEpv00 is most of the sun's cost, and
  // eraAtco13 would evaluate it a second time for the same date).
  double heliocentric[2][3];
  eraEpv00(d.tt1, d.tt2, heliocentric, terms.barycentric);
  for (int i = 0; i < 3; ++i) terms.heliocentric[i] = heliocentric[0][i];
  double bpn[3][3];
  eraPnm06a(d.tt1, d.tt2, bpn);
  eraBpn2xy(bpn, &terms.cip_x, &terms.cip_y);
  terms.cio_s = eraS06(d.tt1, d.tt2, terms.cip_x, terms.cip_y);
  return terms;
}

// eraAtco13's steps (eraApco13 then eraAtciq and eraAtioq, ERFA 2.0), with the Earth's ephemeris
// and the CIP given: the same calls on the same arguments, so the same bits. UT1 = UTC, no polar
// motion, no refraction (pressure 0).
SolarPosition observed(const Dates& d, const TimeTerms& terms, double lat_deg, double lon_deg,
                       double height_m) {
  // The sun's barycentric position: the Earth's barycentric less its heliocentric (AU).
  double sun[3];
  for (int i = 0; i < 3; ++i) sun[i] = terms.barycentric[0][i] - terms.heliocentric[i];
  const double distance_au = eraPm(sun);
  double ra = 0, dec = 0;
  eraC2s(sun, &ra, &dec);
  // Its parallax (arcsec) for ERFA's space motion: the sun seen from the observer, not from the
  // barycentre (eraPmpx moves an object of any distance exactly, as a vector difference).
  const double parallax_arcsec = ERFA_DR2AS / distance_au;
  double ut11 = 0, ut12 = 0;
  if (eraUtcut1(d.utc1, d.utc2, 0.0, &ut11, &ut12) < 0)
    throw std::invalid_argument("solar_position: ERFA cannot convert the time");
  const double era = eraEra00(ut11, ut12);
  const double tio_s = eraSp00(d.tt1, d.tt2);
  double refa = 0, refb = 0;
  eraRefco(0.0, 0.0, 0.0, 0.0, &refa, &refb);
  eraASTROM astrom;
  double barycentric[2][3];
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 3; ++j) barycentric[i][j] = terms.barycentric[i][j];
  double heliocentric[3] = {terms.heliocentric[0], terms.heliocentric[1], terms.heliocentric[2]};
  eraApco(d.tt1, d.tt2, barycentric, heliocentric, terms.cip_x, terms.cip_y, terms.cio_s, era,
          lon_deg * kDeg, lat_deg * kDeg, height_m, 0.0, 0.0, tio_s, refa, refb, &astrom);
  double ri = 0, di = 0;
  eraAtciq(ra, dec, 0.0, 0.0, parallax_arcsec, 0.0, &astrom, &ri, &di);
  double azimuth = 0, zenith = 0, hour_angle = 0, declination = 0, right_ascension = 0;
  eraAtioq(ri, di, &astrom, &azimuth, &zenith, &hour_angle, &declination, &right_ascension);
  SolarPosition position;
  position.elevation_deg = 90.0 - zenith / kDeg;
  position.azimuth_deg = std::fmod(azimuth / kDeg + 360.0, 360.0);
  return position;
}

// Seconds between the knots of solar_position_interpolated.
constexpr double kKnotS = 60.0;

// One knot: a whole minute of the time stamps, its TT and its terms.
struct Knot {
  std::int64_t minute = 0;
  Dates dates;
  TimeTerms terms{};
};

// The four knots met last on this thread (once all four are held, a new one takes the slot of
// its minute modulo 4): a track's times advance, so its shots meet the same two again and again.
const Knot& knot_at(std::int64_t minute) {
  thread_local std::array<Knot, 4> kept;
  thread_local int count = 0;
  for (int k = 0; k < count; ++k)
    if (kept[k].minute == minute) return kept[k];
  const int slot = count < static_cast<int>(kept.size()) ? count++ : static_cast<int>(minute & 3);
  Knot& knot = kept[slot];
  knot.minute = minute;
  knot.dates = dates_of(static_cast<double>(minute) * kKnotS);
  knot.terms = time_terms(knot.dates);
  return knot;
}

}  // namespace

SolarPosition solar_position(double time_s, double lat_deg, double lon_deg, double height_m) {
  check_arguments(time_s, lat_deg, lon_deg, height_m);
  const Dates d = dates_of(time_s);
  return observed(d, time_terms(d), lat_deg, lon_deg, height_m);
}

SolarPosition solar_position_interpolated(double time_s, double lat_deg, double lon_deg,
                                          double height_m) {
  check_arguments(time_s, lat_deg, lon_deg, height_m);
  const Dates d = dates_of(time_s);
  const auto minute = static_cast<std::int64_t>(std::floor(time_s / kKnotS));
  // Copies: the second knot may take the first's slot.
  const Knot a = knot_at(minute);
  const Knot b = knot_at(minute + 1);
  // The fraction of the way in TT (a leap second makes a minute of 61 s of TT).
  const double t = ((d.tt1 - a.dates.tt1) + (d.tt2 - a.dates.tt2)) /
                   ((b.dates.tt1 - a.dates.tt1) + (b.dates.tt2 - a.dates.tt2));
  auto lerp = [t](double x, double y) { return x + t * (y - x); };
  TimeTerms terms{};
  for (int i = 0; i < 3; ++i) {
    terms.heliocentric[i] = lerp(a.terms.heliocentric[i], b.terms.heliocentric[i]);
    for (int j = 0; j < 2; ++j)
      terms.barycentric[j][i] = lerp(a.terms.barycentric[j][i], b.terms.barycentric[j][i]);
  }
  terms.cip_x = lerp(a.terms.cip_x, b.terms.cip_x);
  terms.cip_y = lerp(a.terms.cip_y, b.terms.cip_y);
  terms.cio_s = lerp(a.terms.cio_s, b.terms.cio_s);
  return observed(d, terms, lat_deg, lon_deg, height_m);
}

}  // namespace glaswave
