// The sun's elevation and azimuth against a published reference: the worked example of NREL's
// Solar Position Algorithm (Reda, I. and Andreas, A., 2004, "Solar position algorithm for solar
// radiation applications", Solar Energy 76, 577-589; NREL/TP-560-34302, Table A5.1), whose
// stated uncertainty is +-0.0003 deg.
#include "footprints/solar_position.hpp"

#include <erfa.h>
#include <erfam.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>
#include <string>

#include "core/glas_time.hpp"

namespace glaswave {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// SPA's example: 2003-10-17 12:30:30 local time at UTC-7 (19:30:30 UTC), 39.742476 N,
// 105.1786 W, 1830.14 m; 820 mbar and 11 C for its refraction. Table A5.1 gives the topocentric
// elevation without refraction e0 = 39.872046 deg, the zenith angle with refraction
// 50.11162 deg and the azimuth (eastward from north) 194.34024 deg. SPA takes dUT1 = 0 and
// dT = 67 s where ERFA's leap seconds give TT - UTC = 64.184 s: the 2.8 s apart move the sun by
// 3e-5 deg.
TEST(SolarPosition, MatchesTheSolarPositionAlgorithmsExampleWithinItsUncertainty) {
  const double t = parse_iso8601_utc("2003-10-17T19:30:30Z");
  const SolarPosition sun = solar_position(t, 39.742476, -105.1786, 1830.14);
  constexpr double tolerance_deg = 0.0003;
  EXPECT_NEAR(sun.elevation_deg, 39.872046, tolerance_deg);
  EXPECT_NEAR(sun.azimuth_deg, 194.34024, tolerance_deg);
  // SPA's refraction (its eq. 42), applied here to our geometric elevation, gives its zenith.
  const double e0 = sun.elevation_deg;
  const double refraction_deg = (820.0 / 1010.0) * (283.0 / (273.0 + 11.0)) * 1.02 /
                                (60.0 * std::tan((e0 + 10.3 / (e0 + 5.11)) * kDeg));
  EXPECT_NEAR(90.0 - (e0 + refraction_deg), 50.11162, tolerance_deg);
}

// Checks that need no table: the sun is below the horizon at local midnight and near the zenith
// at the subsolar point (at the March 2005 equinox, 2005-03-20T12:33Z, the sun stood over the
// equator; with the equation of time at -7.5 min the sun runs late, and local noon was at
// longitude -(33 - 7.5) / 60 * 15 = -6.4 deg).
TEST(SolarPosition, IsBelowTheHorizonAtMidnightAndOverheadAtTheSubsolarPoint) {
  const double noon = parse_iso8601_utc("2005-03-20T12:33:00Z");
  EXPECT_GT(solar_position(noon, 0.0, -6.4).elevation_deg, 89.5);
  EXPECT_LT(solar_position(noon, 0.0, 173.6).elevation_deg, -89.5);
  // 53.6 deg of hour angle before noon, on the equator: in the east, that far from the zenith.
  const SolarPosition morning = solar_position(noon, 0.0, -60.0);
  EXPECT_NEAR(morning.azimuth_deg, 90.0, 0.5);
  EXPECT_NEAR(morning.elevation_deg, 90.0 - 53.6, 0.5);
  EXPECT_THROW(solar_position(std::nan(""), 0.0, 0.0), std::invalid_argument);
  EXPECT_THROW(solar_position(1e12, 0.0, 0.0), std::invalid_argument);
}

// solar_position takes eraAtco13's steps with one evaluation of the Earth's ephemeris instead of
// two: its angles must be eraAtco13's to the bit (the products' solar_elevation and
// solar_azimuth unchanged), over dates from 1950 to 2090, on every side of the globe, at the
// heights of the sea and of mountains.
TEST(SolarPosition, IsEraAtco13sToTheBit) {
  constexpr double glas_epoch_jd = 2451545.0;
  int compared = 0;
  for (double time_s = -1.5e9; time_s < 2.8e9; time_s += 1.1e8 + 0.025) {
    for (double lat_deg = -85.0; lat_deg <= 85.0; lat_deg += 34.0) {
      for (double lon_deg = -179.0; lon_deg < 180.0; lon_deg += 71.5) {
        const double height_m = lat_deg > 0.0 ? 4100.0 : -20.0;
        const SolarPosition sun = solar_position(time_s, lat_deg, lon_deg, height_m);
        // The reference: the sun's barycentric place from eraEpv00, then eraAtco13 alone.
        const double days = time_s / 86400.0;
        const double utc1 = glas_epoch_jd + std::floor(days), utc2 = days - std::floor(days);
        double tai1, tai2, tt1, tt2, heliocentric[2][3], barycentric[2][3], place[3];
        ASSERT_GE(eraUtctai(utc1, utc2, &tai1, &tai2), 0);
        ASSERT_EQ(eraTaitt(tai1, tai2, &tt1, &tt2), 0);
        eraEpv00(tt1, tt2, heliocentric, barycentric);
        for (int i = 0; i < 3; ++i) place[i] = barycentric[0][i] - heliocentric[0][i];
        double ra, dec, azimuth, zenith, hour_angle, declination, right_ascension, eo;
        eraC2s(place, &ra, &dec);
        ASSERT_GE(eraAtco13(ra, dec, 0.0, 0.0, ERFA_DR2AS / eraPm(place), 0.0, utc1, utc2, 0.0,
                            lon_deg * kDeg, lat_deg * kDeg, height_m, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
                            &azimuth, &zenith, &hour_angle, &declination, &right_ascension, &eo),
                  0);
        EXPECT_EQ(sun.elevation_deg, 90.0 - zenith / kDeg) << time_s << " " << lat_deg;
        EXPECT_EQ(sun.azimuth_deg, std::fmod(azimuth / kDeg + 360.0, 360.0)) << time_s;
        ++compared;
      }
    }
  }
  EXPECT_GT(compared, 500);
}

// solar_position_interpolated takes ERFA's slow terms (the Earth's ephemeris, precession-
// nutation, the CIO locator) at whole minutes and interpolates them; its header promises its
// angles within 1e-9 deg of solar_position's. The bound: the Earth's acceleration toward the sun,
// 5.9e-3 m/s^2, leaves a chord over a minute at most a h^2 / 8 = 2.7 m from the orbit, 1.8e-11
// rad at 1 AU, 1e-9 deg; the nutation's fastest large term (0.1", 13.7 days) bends 1e-14 rad
// over a minute; the place of the observer is exact. Checked at 4-second steps across minutes,
// over a leap second (2016-12-31T23:59:60Z) and over dates from 1952 to 2088 at places around
// the globe. The azimuth's error is weighed by cos(elevation): near the zenith a tiny shift of
// the sun turns its azimuth by any amount, while the direction moves as little.
TEST(SolarPosition, InterpolatedIsWithin1e9DegOfExact) {
  constexpr double bound_deg = 1e-9;
  const double leap_s = parse_iso8601_utc("2016-12-31T23:58:30Z");
  double worst_elevation_deg = 0.0, worst_azimuth_deg = 0.0;
  int compared = 0;
  auto compare = [&](double time_s, double lat_deg, double lon_deg, double height_m) {
    const SolarPosition exact = solar_position(time_s, lat_deg, lon_deg, height_m);
    const SolarPosition near = solar_position_interpolated(time_s, lat_deg, lon_deg, height_m);
    const double elevation_deg = std::abs(near.elevation_deg - exact.elevation_deg);
    const double azimuth_deg =
        std::abs(std::remainder(near.azimuth_deg - exact.azimuth_deg, 360.0)) *
        std::cos(exact.elevation_deg * kDeg);
    worst_elevation_deg = std::max(worst_elevation_deg, elevation_deg);
    worst_azimuth_deg = std::max(worst_azimuth_deg, azimuth_deg);
    EXPECT_LE(elevation_deg, bound_deg) << time_s << " " << lat_deg << " " << lon_deg;
    EXPECT_LE(azimuth_deg, bound_deg) << time_s << " " << lat_deg << " " << lon_deg;
    ++compared;
  };
  for (double start_s : {-1.5e9, -3.3e8, 1.7e8, leap_s, 7.7e8, 2.7e9}) {
    for (double step_s = 0.0; step_s < 180.0; step_s += 4.0 + 1.0 / 64.0) {
      const double lat_deg = -80.0 + std::fmod(7.3 * step_s, 160.0);
      const double lon_deg = -179.0 + std::fmod(13.1 * step_s + start_s * 1e-7, 358.0);
      compare(start_s + step_s, lat_deg, lon_deg, 30.0 * step_s - 100.0);
    }
  }
  EXPECT_GT(compared, 250);
  RecordProperty("worst_elevation_deg", std::to_string(worst_elevation_deg));
  RecordProperty("worst_azimuth_deg", std::to_string(worst_azimuth_deg));
  std::printf("interpolated sun: worst %.3g deg in elevation, %.3g deg in azimuth (x cos el)\n",
              worst_elevation_deg, worst_azimuth_deg);
}

// The minutes kept per thread do not show in the result: the same arguments give the same
// angles whichever minutes were met before.
TEST(SolarPosition, InterpolatedDependsOnItsArgumentsAlone) {
  const double time_s = 5.0e8 + 17.25;
  const SolarPosition first = solar_position_interpolated(time_s, 45.0, 7.0, 300.0);
  for (double other_s : {-2.0e9, 2.0e9, 3.0e8, 5.0e8 + 90.0, 5.0e8 - 45.0})
    solar_position_interpolated(other_s, 10.0, 20.0);
  const SolarPosition again = solar_position_interpolated(time_s, 45.0, 7.0, 300.0);
  EXPECT_EQ(first.elevation_deg, again.elevation_deg);
  EXPECT_EQ(first.azimuth_deg, again.azimuth_deg);
  EXPECT_THROW(solar_position_interpolated(std::nan(""), 0.0, 0.0), std::invalid_argument);
  EXPECT_THROW(solar_position_interpolated(1e12, 0.0, 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace glaswave
