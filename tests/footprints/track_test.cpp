// Track geometry: pass spacing along the geodesic, pointing of off-nadir shots, orbit tracks
// that keep only the shots on the terrain, each checked by recomputing from positions with
// GeographicLib independently of the code under test.
#include "footprints/track.hpp"

#include <gtest/gtest.h>

#include <GeographicLib/Geodesic.hpp>
#include <GeographicLib/GeodesicLine.hpp>
#include <GeographicLib/LocalCartesian.hpp>
#include <cmath>
#include <numbers>

#include "core/error.hpp"
#include "tests/footprints/test_terrains.hpp"

namespace glaswave {
namespace {

constexpr double deg = std::numbers::pi / 180.0;

// Off-nadir angle, azimuth and range of the beam, recomputed in GeographicLib's east-north-up
// frame at the spacecraft from the spacecraft and footprint positions alone (0.001 deg, 1 cm).
void expect_pointing(const Footprint& footprint, double off_nadir_deg, double azimuth_deg) {
  ASSERT_TRUE(footprint.on_terrain);
  const GeographicLib::LocalCartesian at_spacecraft(
      footprint.spacecraft.lat_deg, footprint.spacecraft.lon_deg, footprint.spacecraft.h_m);
  double east = 0, north = 0, up = 0;
  at_spacecraft.Forward(footprint.ground.lat_deg, footprint.ground.lon_deg, footprint.ground.h_m,
                        east, north, up);
  EXPECT_NEAR(std::atan2(std::hypot(east, north), -up) / deg, off_nadir_deg, 1e-3);
  if (off_nadir_deg > 0.0) {
    const double azimuth = std::atan2(east, north) / deg;
    EXPECT_NEAR(std::remainder(azimuth - azimuth_deg, 360.0), 0.0, 1e-3);
  }
  EXPECT_NEAR(std::sqrt(east * east + north * north + up * up), footprint.range_m, 0.01);
  EXPECT_NEAR(footprint.off_nadir_deg, off_nadir_deg, 1e-3);
}

TEST(PointsTrack, OffNadirShotsLandOnTheirTargets) {
  const PlaneTerrain terrain({34.3, -118.2, 800.0, 15.0, 30.0});
  TrackSettings track;
  track.type = TrackType::points;
  track.points = {{34.3, -118.2}, {34.301, -118.199}, {34.29, -118.21}};
  track.altitude_m = 600000.0;
  track.off_nadir_deg = 4.0;
  track.pointing_azimuth_deg = 250.0;
  const Track planned(track, terrain);
  ASSERT_EQ(planned.size(), 3);
  for (std::int64_t i = 0; i < planned.size(); ++i) {
    const Footprint f = planned.footprint(i);
    ASSERT_TRUE(f.on_terrain);
    double distance_m = 0;
    GeographicLib::Geodesic::WGS84().Inverse(f.ground.lat_deg, f.ground.lon_deg,
                                             track.points[i].lat_deg, track.points[i].lon_deg,
                                             distance_m);
    EXPECT_LT(distance_m, 0.01);
    EXPECT_NEAR(f.ground.h_m, terrain.height_m(f.ground.lat_deg, f.ground.lon_deg), 0.01);
    EXPECT_NEAR(f.spacecraft.h_m, 600000.0, 0.01);
    expect_pointing(f, 4.0, 250.0);
  }
}

TEST(PassTrack, ShotsAreSpacedAlongTheGeodesicAndInTime) {
  const PlaneTerrain terrain({60.0, 10.0, 0.0, 0.0, 0.0});
  TrackSettings track;
  track.type = TrackType::pass;
  track.start_lat_deg = 60.0;
  track.start_lon_deg = 10.0;
  track.heading_deg = 10.0;
  track.shots = 200;
  track.spacing_m = 172.0;
  track.rate_hz = 40.0;
  track.start_time_s = 1000.0;
  const Track planned(track, terrain);
  const std::vector<Footprint> footprints = planned.footprints(0, planned.size());
  ASSERT_EQ(footprints.size(), 200u);
  // The geodesic from the start along the heading, as GeographicLib traces it.
  const GeographicLib::GeodesicLine line = GeographicLib::Geodesic::WGS84().Line(60.0, 10.0, 10.0);
  for (std::size_t i = 1; i < footprints.size(); ++i) {
    double distance_m = 0, azimuth1 = 0, azimuth2 = 0;
    GeographicLib::Geodesic::WGS84().Inverse(
        footprints[i - 1].ground.lat_deg, footprints[i - 1].ground.lon_deg,
        footprints[i].ground.lat_deg, footprints[i].ground.lon_deg, distance_m, azimuth1, azimuth2);
    EXPECT_NEAR(distance_m, 172.0, 0.01);
    // The heading is kept: each step goes along the geodesic's own azimuth there.
    double lat = 0, lon = 0, line_azimuth = 0;
    line.Position(172.0 * (i - 1), lat, lon, line_azimuth);
    EXPECT_NEAR(azimuth1, line_azimuth, 1e-5) << i;
    EXPECT_NEAR(footprints[i].time_s - footprints[i - 1].time_s, 1.0 / 40.0, 1e-9);
    expect_pointing(footprints[i], 0.0, 0.0);
  }
  EXPECT_DOUBLE_EQ(footprints[0].time_s, 1000.0);
  // A shard of the track is the same shots.
  const auto shard = Track(track, terrain).footprints(3, 5);
  ASSERT_EQ(shard.size(), 2u);
  EXPECT_EQ(shard[0].shot_number, 3);
  EXPECT_DOUBLE_EQ(shard[0].ground.lat_deg, footprints[3].ground.lat_deg);
}

TEST(PassTrack, OffNadirShotsPointAsConfigured) {
  const PlaneTerrain terrain({-20.0, 140.0, 300.0, 10.0, 45.0});
  TrackSettings track;
  track.start_lat_deg = -20.0;
  track.start_lon_deg = 140.0;
  track.heading_deg = 190.0;
  track.shots = 20;
  track.off_nadir_deg = 3.0;
  track.pointing_azimuth_deg = 100.0;
  const Track planned(track, terrain);
  for (std::int64_t i = 0; i < planned.size(); ++i) {
    const Footprint f = planned.footprint(i);
    expect_pointing(f, 3.0, 100.0);
    EXPECT_NEAR(f.ground.h_m, terrain.height_m(f.ground.lat_deg, f.ground.lon_deg), 0.01);
  }
}

TEST(Track, ATrackThatNeverMeetsTheTerrainIsAnInputError) {
  const testing::CapTerrain terrain(0.0, 0.0, 5000.0);
  TrackSettings track;
  track.start_lat_deg = 10.0;  // 1100 km from the only ground
  track.shots = 3;
  try {
    const Track planned(track, terrain);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.exit_status(), 3);
    EXPECT_EQ(e.in_section("/track").place(), "/track");
    EXPECT_NE(std::string(e.what()).find("never meets the terrain"), std::string::npos) << e.what();
  }
  // A pass that leaves the ground keeps every shot, flagged where it misses.
  track.start_lat_deg = 0.0;
  track.spacing_m = 2000.0;
  track.shots = 5;
  const Track leaving(track, terrain);
  ASSERT_EQ(leaving.size(), 5);
  EXPECT_TRUE(leaving.footprint(2).on_terrain);
  EXPECT_FALSE(leaving.footprint(3).on_terrain);
}

// An ICESat-like orbit over level ground everywhere: every shot is kept, and the footprints reach
// the latitude where the orbit turns, 180 - 94 = 86 degrees geocentric.
TEST(OrbitTrack, IcesatOrbitReachesLatitude86) {
  const testing::LevelTerrain terrain(0.0);
  TrackSettings track;
  track.type = TrackType::orbit;
  track.orbit.semi_major_axis_m = 6378137.0 + 600000.0;
  track.orbit.inclination_deg = 94.0;
  track.orbit.raan_deg = 30.0;
  track.start_time_s = track.orbit.epoch_s = 1.8e8;
  track.rate_hz = 1.0;
  track.shots = 5800;  // a little more than one revolution (5801 s)
  const Track planned(track, terrain);
  ASSERT_EQ(planned.size(), 5800);
  double max_lat = -90, min_lat = 90;
  for (std::int64_t record = 0; record < planned.size(); ++record) {
    const Footprint f = planned.footprint(record);
    ASSERT_TRUE(f.on_terrain);
    EXPECT_NEAR(f.time_s - track.start_time_s, static_cast<double>(record), 1e-6);
    max_lat = std::max(max_lat, f.ground.lat_deg);
    min_lat = std::min(min_lat, f.ground.lat_deg);
  }
  // Geodetic latitude under the point of geocentric latitude 86 at the orbit's radius.
  const double r = track.orbit.semi_major_axis_m;
  const Geodetic turn =
      geodetic_from_ecef({r * std::cos(86.0 * deg), 0.0, r * std::sin(86.0 * deg)});
  EXPECT_NEAR(max_lat, turn.lat_deg, 1e-3);
  EXPECT_NEAR(min_lat, -turn.lat_deg, 1e-3);
  EXPECT_GT(max_lat, 86.0);
}

// An orbit over one patch of ground: shot numbers are the index in the time sequence, only the
// shots over the patch are records, and selecting shot numbers selects those records.
TEST(OrbitTrack, KeepsOnlyTheShotsOnTheTerrainWithStableShotNumbers) {
  TrackSettings track;
  track.type = TrackType::orbit;
  track.orbit.semi_major_axis_m = 6378137.0 + 600000.0;
  track.orbit.inclination_deg = 94.0;
  track.rate_hz = 40.0;
  track.shots = 40 * 600;  // ten minutes
  // The ground lies where the spacecraft is after five minutes.
  const Orbit orbit(track.orbit);
  const Geodetic under = geodetic_from_ecef(orbit.ecef_position_m(300.0));
  const testing::CapTerrain terrain(under.lat_deg, under.lon_deg, 50000.0, 1500.0);

  const Track planned(track, terrain);
  ASSERT_GT(planned.size(), 0);
  ASSERT_LT(planned.size(), planned.sequence_length());
  EXPECT_EQ(planned.sequence_length(), 24000);
  // 100 km of ground at about 6.9 km/s ground speed: about 14.5 s of shots.
  EXPECT_NEAR(planned.size() / 40.0, 100.0 / 6.9, 0.5);
  for (std::int64_t record = 0; record < planned.size(); ++record) {
    const Footprint f = planned.footprint(record);
    EXPECT_EQ(f.shot_number, planned.shot_number(record));
    EXPECT_TRUE(f.on_terrain);
    EXPECT_NEAR(f.ground.h_m, 1500.0, 0.01);
    EXPECT_DOUBLE_EQ(f.time_s, f.shot_number / 40.0);
    if (record > 0) {
      EXPECT_GT(f.shot_number, planned.shot_number(record - 1));
    }
  }
  EXPECT_FALSE(planned.locate_shot(0).on_terrain);
  // --shots A:B selects by shot number.
  const std::int64_t first_kept = planned.shot_number(0);
  const auto [first, last] = planned.records_of_shots(first_kept + 10, first_kept + 30);
  EXPECT_EQ(first, 10);
  EXPECT_EQ(last, 30);
  EXPECT_EQ(planned.records_of_shots(0, first_kept),
            std::make_pair(std::int64_t{0}, std::int64_t{0}));
  EXPECT_EQ(planned.records_of_shots(0, 1 << 30), std::make_pair(std::int64_t{0}, planned.size()));

  // An orbit that never passes over the ground is an error naming the track.
  track.shots = 40 * 60;
  try {
    const Track missing(track, terrain);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.exit_status(), 3);
    EXPECT_NE(std::string(e.what()).find("never meets the terrain"), std::string::npos) << e.what();
  }
}

TEST(IntersectTerrain, MeetsATiltedPlaneAtItsHeight) {
  const PlaneTerrain terrain({0.0, 0.0, 2000.0, 35.0, 180.0});
  const Geodetic spacecraft{0.001, 0.0, 600000.0};
  const Vec3 beam = pointing_direction(spacecraft, 3.0, 0.0);
  const auto hit = intersect_terrain(terrain, ecef_from_geodetic(spacecraft), beam);
  ASSERT_TRUE(hit.has_value());
  const Geodetic ground = geodetic_from_ecef(*hit);
  EXPECT_NEAR(ground.h_m, terrain.height_m(ground.lat_deg, ground.lon_deg), 0.01);
  // The hit lies on the beam.
  const Vec3 to_hit = *hit - ecef_from_geodetic(spacecraft);
  EXPECT_NEAR(norm(cross(to_hit, beam)), 0.0, 1e-3);
}

TEST(IntersectTerrain, ARayPointingAwayNeverMeetsIt) {
  const PlaneTerrain terrain({0.0, 0.0, 0.0, 0.0, 0.0});
  const Geodetic spacecraft{0.0, 0.0, 600000.0};
  EXPECT_FALSE(intersect_terrain(terrain, ecef_from_geodetic(spacecraft), enu_axes(0.0, 0.0)[2])
                   .has_value());
  // Nor does one that passes beside the Earth.
  EXPECT_FALSE(intersect_terrain(terrain, ecef_from_geodetic(spacecraft), enu_axes(0.0, 0.0)[0])
                   .has_value());
}

}  // namespace
}  // namespace glaswave
