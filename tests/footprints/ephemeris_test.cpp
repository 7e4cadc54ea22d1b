// Ephemeris tracks: a CSV of times and Earth-fixed positions read into shots, and every bad
// file refused with its path and line (exit status 3).
#include "footprints/ephemeris.hpp"

#include <gtest/gtest.h>

#include <GeographicLib/LocalCartesian.hpp>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "core/error.hpp"
#include "core/glas_time.hpp"
#include "footprints/track.hpp"
#include "tests/footprints/test_terrains.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

namespace fs = std::filesystem;

class Ephemeris : public ::testing::Test {
 protected:
  fs::path write(const std::string& text) {
    const fs::path file = dir_ / "track.csv";
    std::ofstream(file) << text;
    return file;
  }

  // The message of the input error that reading `text` raises.
  std::string error_of(const std::string& text) {
    const fs::path file = write(text);
    try {
      read_ephemeris(file);
    } catch (const Error& e) {
      EXPECT_EQ(e.exit_status(), 3) << e.what();
      return e.what();
    }
    ADD_FAILURE() << "no error for:\n" << text;
    return {};
  }

  test_support::ScratchDir dir_{"glaswave_ephemeris"};
};

std::string position_text(const Geodetic& point) {
  const Vec3 p = ecef_from_geodetic(point);
  char buffer[128];
  std::snprintf(buffer, sizeof buffer, "%.4f,%.4f,%.4f", p[0], p[1], p[2]);
  return buffer;
}

TEST_F(Ephemeris, ShotsComeFromTheRowsWithTheirTimesPositionsAndPointing) {
  const Geodetic a{45.0, 7.0, 600000.0}, b{45.01, 7.0, 600000.0};
  // The second shot points 2 degrees off nadir toward the east, given as an ECEF vector.
  const auto axes = enu_axes(b.lat_deg, b.lon_deg);
  const double tilt = 2.0 * std::numbers::pi / 180.0;
  const Vec3 pointing =
      (3.0 * std::sin(tilt)) * axes[0] + (-3.0 * std::cos(tilt)) * axes[2];  // any length
  char pointing_text[128];
  std::snprintf(pointing_text, sizeof pointing_text, "%.12f,%.12f,%.12f", pointing[0], pointing[1],
                pointing[2]);
  const fs::path file = write(
      "# ICESat-like shots\n"
      "x_m, y_m, z_m, time, pointing_x, pointing_y, pointing_z\r\n"
      "\n" +
      position_text(a) + ",2005-10-21T12:00:00.025Z,0,0,-1\n" + position_text(b) +
      ", 183124800.05 ," + pointing_text + "\n");
  TrackSettings settings;
  settings.type = TrackType::ephemeris;
  settings.ephemeris = file.string();
  const testing::LevelTerrain terrain(250.0);
  const Track track(settings, terrain);
  ASSERT_EQ(track.size(), 2);
  const Footprint first = track.footprint(0), second = track.footprint(1);
  EXPECT_DOUBLE_EQ(first.time_s, parse_iso8601_utc("2005-10-21T12:00:00.025Z"));
  EXPECT_DOUBLE_EQ(second.time_s, 183124800.05);
  EXPECT_NEAR(norm(first.spacecraft_ecef - ecef_from_geodetic(a)), 0.0, 1e-3);
  ASSERT_TRUE(first.on_terrain && second.on_terrain);
  // (0, 0, -1) is toward the Earth's axis southward, not nadir; the footprint lies along it.
  EXPECT_NEAR(norm(cross(ecef_from_geodetic(first.ground) - first.spacecraft_ecef, {0, 0, -1})),
              0.0, 1e-3);
  EXPECT_NEAR(first.ground.h_m, 250.0, 0.01);
  // The second: 2 degrees east of nadir, checked in GeographicLib's frame at the spacecraft.
  EXPECT_NEAR(second.off_nadir_deg, 2.0, 1e-6);
  const GeographicLib::LocalCartesian local(b.lat_deg, b.lon_deg, b.h_m);
  double east = 0, north = 0, up = 0;
  local.Forward(second.ground.lat_deg, second.ground.lon_deg, second.ground.h_m, east, north, up);
  EXPECT_NEAR(std::atan2(east, -up) * 180.0 / std::numbers::pi, 2.0, 1e-3);
  EXPECT_NEAR(north, 0.0, 0.01);
  EXPECT_NEAR(std::sqrt(east * east + north * north + up * up), second.range_m, 0.01);
}

// Issue 42: "any length" held up to about 1e154, where the squares overflowed and a vector of
// 1e300 was called zero. Scaled by 1e300 and by 1e-300, it points 2 degrees east of nadir.
TEST_F(Ephemeris, APointingVectorOfAnyLengthPointsAlike) {
  const Geodetic b{45.01, 7.0, 600000.0};
  const auto axes = enu_axes(b.lat_deg, b.lon_deg);
  const double tilt = 2.0 * std::numbers::pi / 180.0;
  const Vec3 pointing = std::sin(tilt) * axes[0] + (-std::cos(tilt)) * axes[2];
  for (const char* scale : {"e300", "e-300"}) {
    char text[160];
    std::snprintf(text, sizeof text, "%.15f%s,%.15f%s,%.15f%s", pointing[0], scale, pointing[1],
                  scale, pointing[2], scale);
    const fs::path file = write("time,x_m,y_m,z_m,pointing_x,pointing_y,pointing_z\n0," +
                                position_text(b) + "," + text + "\n");
    TrackSettings settings;
    settings.type = TrackType::ephemeris;
    settings.ephemeris = file.string();
    const testing::LevelTerrain terrain(250.0);
    const Track track(settings, terrain);
    ASSERT_EQ(track.size(), 1);
    EXPECT_NEAR(track.footprint(0).off_nadir_deg, 2.0, 1e-6) << scale;
  }
}

TEST_F(Ephemeris, WithoutPointingShotsPointAsAPassDoes) {
  const Geodetic a{-33.0, 151.0, 590000.0};
  const fs::path file = write("time,x_m,y_m,z_m\n0," + position_text(a) + "\n");
  TrackSettings settings;
  settings.type = TrackType::ephemeris;
  settings.ephemeris = file.string();
  settings.off_nadir_deg = 1.5;
  settings.pointing_azimuth_deg = 300.0;
  const testing::LevelTerrain terrain(0.0);  // the track keeps a reference: not a temporary
  const Track track(settings, terrain);
  const Footprint f = track.footprint(0);
  ASSERT_TRUE(f.on_terrain);
  EXPECT_NEAR(
      off_nadir_angle_deg(f.spacecraft_ecef, ecef_from_geodetic(f.ground) - f.spacecraft_ecef), 1.5,
      1e-6);
  EXPECT_DOUBLE_EQ(f.off_nadir_deg, 1.5);
}

TEST_F(Ephemeris, ErrorsNameTheFileAndLine) {
  const std::string good = position_text({10.0, 10.0, 600000.0});
  const std::string path = (dir_ / "track.csv").string();
  struct Case {
    std::string text, expected;
  };
  const std::vector<Case> cases = {
      {"time,x_m,y_m,z_m\n0," + good + "\n1,7000000,abc,0\n",
       path + ":3: y_m: expected a finite number, got \"abc\""},
      {"time,x_m,y_m\n0,1,2\n", path + ":1: missing column \"z_m\""},
      {"# comment\n\ntime,x_m,y_m,z_m\n0," + good + "\n2005-13-01T00:00:00Z," + good + "\n",
       path + ":5: time: expected seconds since 2000-01-01T12:00:00Z or ISO 8601"},
      {"time,x_m,y_m,z_m\n2005-10-21T12:00:00," + good + "\n", path + ":2: time:"},
      {"time,x_m,y_m,z_m\n0," + good + ",5\n",
       path + ":2: expected 4 fields as in the header, got 5"},
      {"time,x_m,y_m,z_m,px\n", path + ":1: column 5 is not a column name (\"px\")"},
      {"time,x_m,y_m,z_m,pointing_x\n", path + ":1: the pointing vector needs all three columns"},
      {"time,x_m,y_m,z_m,time\n", path + ":1: column \"time\" appears twice"},
      {"time,x_m,y_m,z_m\n0,6978.137,0,0\n", path + ":2: the spacecraft position is"},
      {"time,x_m,y_m,z_m,pointing_x,pointing_y,pointing_z\n0," + good + ",0,0,0\n",
       path + ":2: the pointing vector is zero"},
      {"time,x_m,y_m,z_m\n0,nan,0,0\n", path + ":2: x_m: expected a finite number"},
      {"", path + ": empty ephemeris file"},
      {"time,x_m,y_m,z_m\n", path + ": the ephemeris file holds no shot"},
  };
  for (const Case& c : cases) {
    const std::string message = error_of(c.text);
    EXPECT_EQ(message.rfind(c.expected, 0), 0u)
        << "got: " << message << "\nexpected: " << c.expected;
  }
  // A missing file names the file.
  try {
    read_ephemeris(dir_ / "missing.csv");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.place(), (dir_ / "missing.csv").string());
    EXPECT_EQ(e.exit_status(), 3);
  }
}

}  // namespace
}  // namespace glaswave
