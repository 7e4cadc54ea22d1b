// The sun's position against the almanac: the elevation at the North Pole is the declination,
// which is +-23.44 degrees at the solstices and 0 at the equinox (their instants from the US Naval
// Observatory's tables); at the date of the equation of time's maximum (16.4 min on 3 November)
// the sun crosses the Greenwich meridian, due south, at 11:43:36 UTC.
#include "footprints/sun_position.hpp"

#include <gtest/gtest.h>

#include "core/glas_time.hpp"

namespace glaswave {
namespace {

double at(const char* iso) { return parse_iso8601_utc(iso); }

// The obliquity of the ecliptic in 2018-2019 (IAU 2006: 23.4393 - 0.0130 T, T in centuries).
constexpr double kObliquityDeg = 23.4366;

TEST(SunPosition, PoleElevationIsTheDeclinationAtTheSolsticesAndTheEquinox) {
  EXPECT_NEAR(sun_position(at("2018-06-21T10:07:00Z"), 90.0, 0.0).elevation_deg, kObliquityDeg,
              0.02);
  EXPECT_NEAR(sun_position(at("2018-12-21T22:23:00Z"), 90.0, 120.0).elevation_deg, -kObliquityDeg,
              0.02);
  EXPECT_NEAR(sun_position(at("2019-03-20T21:58:00Z"), 90.0, -60.0).elevation_deg, 0.0, 0.02);
}

// 0.25 degree of azimuth at 51.5 N near noon is about 30 s of time.
TEST(SunPosition, TheSunIsDueSouthAtApparentNoon) {
  const SunPosition noon = sun_position(at("2019-11-03T11:43:36Z"), 51.4779, 0.0);
  EXPECT_NEAR(noon.azimuth_deg, 180.0, 0.25);
  // and highest: a quarter of an hour either side it is lower.
  EXPECT_GT(noon.elevation_deg,
            sun_position(at("2019-11-03T11:28:36Z"), 51.4779, 0.0).elevation_deg);
  EXPECT_GT(noon.elevation_deg,
            sun_position(at("2019-11-03T11:58:36Z"), 51.4779, 0.0).elevation_deg);
}

TEST(SunPosition, RisesInTheEastAndSetsInTheWest) {
  // At the equator at the equinox the sun rises near 06:00 local time due east.
  const SunPosition morning = sun_position(at("2019-03-21T06:30:00Z"), 0.0, 0.0);
  EXPECT_GT(morning.elevation_deg, 0.0);
  EXPECT_NEAR(morning.azimuth_deg, 90.0, 1.0);
  const SunPosition evening = sun_position(at("2019-03-21T17:30:00Z"), 0.0, 0.0);
  EXPECT_NEAR(evening.azimuth_deg, 270.0, 1.0);
  EXPECT_LT(sun_position(at("2019-03-21T00:00:00Z"), 0.0, 0.0).elevation_deg, -80.0);
}

}  // namespace
}  // namespace glaswave
