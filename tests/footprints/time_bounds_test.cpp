// The years a track may have (issue 28): times of +-1e300 s or NaN, from an ephemeris, a
// granule, an ISO 8601 text or a rate of next to nothing, gave nonsense or missing coverage
// attributes; each is refused, naming where it came from.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/error.hpp"
#include "core/glas_time.hpp"
#include "footprints/ephemeris.hpp"
#include "footprints/track.hpp"
#include "tests/footprints/test_terrains.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

TEST(TimeBounds, TheRangeIsFrom1900To2200) {
  EXPECT_EQ(parse_iso8601_utc("1900-01-01T00:00:00Z"), earliest_time_s);
  EXPECT_EQ(format_iso8601_utc(earliest_time_s), "1900-01-01T00:00:00Z");
  EXPECT_EQ(format_iso8601_utc(latest_time_s), "2200-01-01T00:00:00Z");
  EXPECT_NO_THROW(parse_iso8601_utc("2199-12-31T23:59:59Z"));
  EXPECT_THROW(parse_iso8601_utc("1899-12-31T23:59:59Z"), std::invalid_argument);
  EXPECT_THROW(parse_iso8601_utc("2200-01-01T00:00:00Z"), std::invalid_argument);
  EXPECT_THROW(parse_iso8601_utc("9999-01-01T00:00:00Z"), std::invalid_argument);
  EXPECT_EQ(time_out_of_range(0.0), "");
  for (double t : {1e300, -1e300, std::numeric_limits<double>::quiet_NaN(),
                   std::numeric_limits<double>::infinity()})
    EXPECT_NE(time_out_of_range(t), "") << t;
  EXPECT_EQ(time_out_of_range(std::numeric_limits<double>::quiet_NaN()),
            "must be a finite time, got nan");
}

TEST(TimeBounds, AnEphemerisTimeOutsideIsRefusedAtItsLine) {
  const test_support::ScratchDir dir;
  const auto file = dir.write("eph.csv", "time,x_m,y_m,z_m\n0,7000000,0,0\n1e300,7000000,0,0\n");
  try {
    read_ephemeris(file);
    FAIL() << "accepted a time of 1e300 s";
  } catch (const Error& e) {
    EXPECT_EQ(e.exit_status(), 3);
    EXPECT_EQ(e.place(), file.string() + ":3");
    EXPECT_EQ(e.message(),
              "time must be from 1900-01-01T00:00:00Z to 2200-01-01T00:00:00Z, got 1e+300 s "
              "from 2000-01-01T12:00:00Z");
  }
  const auto iso = dir.write("iso.csv", "time,x_m,y_m,z_m\n2999-01-01T00:00:00Z,7000000,0,0\n");
  EXPECT_THROW(read_ephemeris(iso), Error);
}

TEST(TimeBounds, ARateOfNextToNothingIsRefusedAtRateHz) {
  const testing::LevelTerrain terrain(0.0);
  TrackSettings track;
  track.type = TrackType::pass;
  track.start_lat_deg = 46.0;
  track.start_lon_deg = 8.0;
  track.shots = 2;
  track.spacing_m = 172.0;
  track.rate_hz = 1e-300;
  try {
    const Track planned(track, terrain);
    FAIL() << "accepted shots 1e300 s apart";
  } catch (const Error& e) {
    EXPECT_TRUE(e.names_setting());
    EXPECT_EQ(e.place(), "rate_hz");
    EXPECT_EQ(e.exit_status(), 2);
  }
  track.rate_hz = 40.0;
  EXPECT_NO_THROW(Track(track, terrain));
}

}  // namespace
}  // namespace glaswave
