// ISO 8601 UTC text and the GLAS epoch (core/glas_time): parsed and written against dates counted
// here by hand, and the products' six-digit form against what gmtime_r (the C library's calendar,
// a second method) gives for the same POSIX second.
#include "core/glas_time.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <ctime>
#include <limits>
#include <stdexcept>
#include <string>

namespace glaswave {
namespace {

TEST(GlasTime, ParsesAgainstHandComputedValues) {
  EXPECT_EQ(parse_iso8601_utc("2000-01-01T12:00:00Z"), 0.0);  // the GLAS epoch itself
  EXPECT_EQ(parse_iso8601_utc("2000-01-01T00:00:00Z"), -43200.0);
  // 2000-01-01 to 2005-01-01: 2000 and 2004 are leap years, 366+365+365+365+366 = 1827 days;
  // 2005-01-01 to 2005-10-21: Jan..Sep = 31+28+31+30+31+30+31+31+30 = 273 days, plus 20 = 293;
  // 1827 + 293 = 2120 days = 2120 * 86400 s = 183168000 s, both times at 12:00.
  EXPECT_EQ(parse_iso8601_utc("2005-10-21T12:00:00Z"), 183168000.0);
  EXPECT_EQ(parse_iso8601_utc("2005-10-21T12:00:00+00:00"), 183168000.0);
  // 2000 is a leap year: 31 (January) + 29 (February) days to 1 March.
  EXPECT_EQ(parse_iso8601_utc("2000-03-01T12:00:00Z"), 60.0 * 86400.0);
  // The Unix epoch: 946728000 s before the GLAS epoch (10957 days and 12 hours).
  EXPECT_EQ(parse_iso8601_utc("1970-01-01T00:00:00Z"), -(10957.0 * 86400.0 + 43200.0));
  EXPECT_EQ(parse_iso8601_utc("2000-01-01T12:00:00.25Z"), 0.25);
  EXPECT_NEAR(parse_iso8601_utc("2003-02-20T01:02:03.123456Z"),
              // 2000..2002: 366+365+365 = 1096 days; January 31 + 19 days = 50; total 1146 days,
              // from 12:00 to 01:02:03.123456 is -(10*3600 + 57*60 + 56.876544) s.
              1146.0 * 86400.0 - (10 * 3600 + 57 * 60 + 56.876544), 1e-6);
}

TEST(GlasTime, RefusesBadText) {
  for (const char* text : {"", "2005-10-21", "2005-10-21T12:00:00", "2005-10-21 12:00:00Z",
                           "2005-10-21T12:00:00+01:00", "2005-13-01T00:00:00Z",
                           "2005-02-29T00:00:00Z", "2005-10-32T00:00:00Z", "2005-10-21T24:00:00Z",
                           "2005-10-21T12:60:00Z", "2005-10-21T12:00:60Z", "2005-10-21T12:00:00.Z",
                           "05-10-21T12:00:00Z", "2005-10-21T12:00:00Zjunk"}) {
    EXPECT_THROW(parse_iso8601_utc(text), std::invalid_argument) << text;
  }
  EXPECT_NO_THROW(parse_iso8601_utc("2004-02-29T00:00:00Z"));
}

TEST(GlasTime, FormatsAndRoundTrips) {
  EXPECT_EQ(format_iso8601_utc(0.0), "2000-01-01T12:00:00Z");
  EXPECT_EQ(format_iso8601_utc(183168000.0), "2005-10-21T12:00:00Z");
  EXPECT_EQ(format_iso8601_utc(0.25), "2000-01-01T12:00:00.25Z");
  EXPECT_EQ(format_iso8601_utc(-43200.5), "1999-12-31T23:59:59.5Z");
  EXPECT_EQ(format_iso8601_utc(59.9999999), "2000-01-01T12:01:00Z");  // rounds to the microsecond
  for (double s : {-1.0e9, -0.125, 1.0, 1.0e8 + 0.5, 5.0e8}) {
    EXPECT_NEAR(parse_iso8601_utc(format_iso8601_utc(s)), s, 1e-6) << s;
  }
  EXPECT_THROW(format_iso8601_utc(std::numeric_limits<double>::infinity()), std::invalid_argument);
}

// 10957 days from 1970-01-01 to 2000-01-01 (30 years, 7 of them leap: 1972 .. 1996), and 12 h.
TEST(GlasTime, TheEpochInPosixSeconds) {
  EXPECT_EQ(glas_epoch_unix_s, (30 * 365 + 7) * 86400 + 12 * 3600);
}

// What the NetCDF writer's time_coverage_start/end were written with before the formatter came to
// core: the POSIX time as a double, its fraction rounded to the microsecond, the date from
// gmtime_r.
std::string with_gmtime(double seconds_since_glas_epoch) {
  const double unix_s = 946728000.0 + seconds_since_glas_epoch;
  double whole_s = std::floor(unix_s);
  auto micro = static_cast<long>(std::llround((unix_s - whole_s) * 1e6));
  if (micro >= 1000000) {
    whole_s += 1.0;
    micro -= 1000000;
  }
  const auto time = static_cast<std::time_t>(whole_s);
  std::tm utc{};
  gmtime_r(&time, &utc);
  char text[64];
  std::snprintf(text, sizeof text, "%04d-%02d-%02dT%02d:%02d:%02d.%06ldZ", utc.tm_year + 1900,
                utc.tm_mon + 1, utc.tm_mday, utc.tm_hour, utc.tm_min, utc.tm_sec, micro);
  return text;
}

TEST(GlasTime, SixDigitsAsTheProductsWriteThem) {
  EXPECT_EQ(format_iso8601_utc_microseconds(0.0), "2000-01-01T12:00:00.000000Z");
  EXPECT_EQ(format_iso8601_utc_microseconds(183168000.25), "2005-10-21T12:00:00.250000Z");
  EXPECT_EQ(format_iso8601_utc_microseconds(-43200.5), "1999-12-31T23:59:59.500000Z");
  // Every 97th day from 1900 to 2200, at fractions of a 242 Hz track's shots, and the first
  // time a track may have.
  for (double s = earliest_time_s; s < latest_time_s; s += 86400.0 * 97.0 + 1.0 / 242.0 * 37.0)
    EXPECT_EQ(format_iso8601_utc_microseconds(s), with_gmtime(s)) << s;
  EXPECT_EQ(format_iso8601_utc_microseconds(earliest_time_s), "1900-01-01T00:00:00.000000Z");
  EXPECT_THROW(format_iso8601_utc_microseconds(std::nan("")), std::invalid_argument);
}

}  // namespace
}  // namespace glaswave
