// What the shot layer's tests share: a plane terrain, one nadir footprint on it from 600 km,
// and a one-band lidar (the north2010 preset's beam and bins at 1064 nm), as typed settings.
#pragma once

#include <memory>

#include "footprints/track.hpp"
#include "pipeline/shot/shot_simulator.hpp"
#include "terrain/terrain.hpp"

namespace glaswave::testing {

inline constexpr double kLat0 = 45.0, kLon0 = 7.0;

inline std::unique_ptr<Terrain> plane_terrain(double soil_reflectance = 0.25) {
  TerrainSettings terrain;
  terrain.plane = PlaneSettings{kLat0, kLon0, 0.0, 0.0, 0.0};
  terrain.soil_reflectance = {soil_reflectance};
  return make_terrain(terrain);
}

inline Footprint nadir_footprint(const Terrain& terrain) {
  TrackSettings track;
  track.type = TrackType::points;
  track.points = {{kLat0, kLon0}};
  return Track(track, terrain).footprint(0);
}

inline ShotSettings shot_settings(double soil_reflectance, std::int64_t rays = 2000) {
  ShotSettings settings;
  settings.lidar.pulse_sigma_ns = 5.0;
  settings.lidar.divergence_sigma_rad = 0.00011;
  settings.lidar.ifov_rad = 0.0004;
  settings.lidar.telescope_area_m2 = 0.709;
  settings.lidar.bin_ns = 1.0;
  settings.lidar.bins = 544;
  settings.lidar.bands = {{1064.0, 1.0, 1.0, "1064"}};
  settings.transport.rays = rays;
  settings.transport.max_order = 4;
  settings.transport.seed = 3;
  settings.soil_reflectance = {soil_reflectance};
  return settings;
}

inline ReceiverSettings receiver_settings(const ShotSettings& shot, const std::string& kind) {
  ReceiverSettings settings;
  settings.kind = kind;
  settings.lidar = shot.lidar;
  settings.seed = shot.transport.seed;
  return settings;
}

}  // namespace glaswave::testing
