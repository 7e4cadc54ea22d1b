// Track geometry: pass spacing along the geodesic, pointing of off-nadir shots, and the beam
// against the terrain, each checked by recomputing from positions independently.
#include <cmath>
#include <numbers>

#include <GeographicLib/Geodesic.hpp>
#include <gtest/gtest.h>

#include "footprints/track.hpp"

namespace glaswave {
namespace {

constexpr double deg = std::numbers::pi / 180.0;

// Off-nadir angle and azimuth of the beam, recomputed in the spacecraft's own frame.
void expect_pointing(const Footprint& footprint, double off_nadir_deg, double azimuth_deg) {
  const Vec3 beam = normalized(ecef_from_geodetic(footprint.ground) - footprint.spacecraft_ecef);
  const auto axes = enu_axes(footprint.spacecraft.lat_deg, footprint.spacecraft.lon_deg);
  const double down = -dot(beam, axes[2]);
  EXPECT_NEAR(std::acos(down) / deg, off_nadir_deg, 1e-3);
  if (off_nadir_deg > 0.0) {
    double azimuth = std::atan2(dot(beam, axes[0]), dot(beam, axes[1])) / deg;
    if (azimuth < 0) azimuth += 360.0;
    EXPECT_NEAR(azimuth, azimuth_deg, 1e-3);
  }
  EXPECT_NEAR(norm(ecef_from_geodetic(footprint.ground) - footprint.spacecraft_ecef), footprint.range_m, 0.01);
}

TEST(PointsTrack, OffNadirShotsLandOnTheirTargets) {
  const PlaneTerrain terrain({34.3, -118.2, 800.0, 15.0, 30.0});
  TrackSettings track;
  track.type = TrackType::points;
  track.points = {{34.3, -118.2}, {34.301, -118.199}};
  track.altitude_m = 600000.0;
  track.off_nadir_deg = 4.0;
  track.pointing_azimuth_deg = 250.0;
  const auto footprints = plan_track(track, terrain, 0, 2);
  ASSERT_EQ(footprints.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    const Footprint& f = footprints[i];
    ASSERT_TRUE(f.on_terrain);
    double distance_m = 0;
    GeographicLib::Geodesic::WGS84().Inverse(f.ground.lat_deg, f.ground.lon_deg, track.points[i].lat_deg,
                                             track.points[i].lon_deg, distance_m);
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
  track.shots = 5;
  track.spacing_m = 172.0;
  track.rate_hz = 40.0;
  track.start_time_s = 1000.0;
  const auto footprints = plan_track(track, terrain, 0, 5);
  ASSERT_EQ(footprints.size(), 5u);
  for (std::size_t i = 1; i < footprints.size(); ++i) {
    double distance_m = 0, azimuth1 = 0, azimuth2 = 0;
    GeographicLib::Geodesic::WGS84().Inverse(footprints[i - 1].ground.lat_deg, footprints[i - 1].ground.lon_deg,
                                             footprints[i].ground.lat_deg, footprints[i].ground.lon_deg,
                                             distance_m, azimuth1, azimuth2);
    EXPECT_NEAR(distance_m, 172.0, 0.01);
    EXPECT_NEAR(footprints[i].time_s - footprints[i - 1].time_s, 1.0 / 40.0, 1e-9);
    expect_pointing(footprints[i], 0.0, 0.0);
  }
  EXPECT_DOUBLE_EQ(footprints[0].time_s, 1000.0);
  // A shard of the track is the same shots.
  const auto shard = plan_track(track, terrain, 3, 5);
  ASSERT_EQ(shard.size(), 2u);
  EXPECT_EQ(shard[0].shot_number, 3);
  EXPECT_DOUBLE_EQ(shard[0].ground.lat_deg, footprints[3].ground.lat_deg);
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
  EXPECT_FALSE(intersect_terrain(terrain, ecef_from_geodetic(spacecraft), enu_axes(0.0, 0.0)[2]).has_value());
}

}  // namespace
}  // namespace glaswave
