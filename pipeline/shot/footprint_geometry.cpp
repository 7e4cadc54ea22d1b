// The footprint's frame, patch and outline.
#include "pipeline/shot/footprint_geometry.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "footprints/terrain_intersection.hpp"

namespace glaswave {

double patch_half_size_m(double reach_m) { return 1.2 * reach_m + 2.0; }

double estimated_patch_half_size_m(double range_m, double ifov_rad, double slope_deg,
                                   bool vegetation) {
  const double reach_m =
      range_m * std::tan(0.5 * ifov_rad) / std::cos(slope_deg * std::numbers::pi / 180.0);
  return patch_half_size_m(reach_m) + (vegetation ? vegetation_margin_m : 0.0);
}

double beam_fraction_in_view(const LidarSettings& lidar) {
  return LidarModel(lidar).fov_fraction();
}

double brf_scene_half_size_m(double tile_half_size_m, bool periodic) {
  return tile_half_size_m + (periodic ? 5.0 : 100.0);
}

FootprintFrame footprint_frame(const Terrain& terrain, const LidarModel& lidar,
                               const Footprint& footprint) {
  FootprintFrame shot{LocalFrame(footprint.ground), {}, {}};
  shot.geometry.sensor_m = shot.frame.local_from_ecef(footprint.spacecraft_ecef);
  shot.geometry.axis = shot.frame.local_direction(footprint.beam_ecef);
  shot.geometry.range_m = footprint.range_m;
  const double beam_sigma_m = footprint.range_m * lidar.beam_sigma_rad();
  shot.orientation = fit_surface_orientation(terrain, shot.frame, beam_sigma_m, shot.geometry.axis);
  return shot;
}

double traced_patch_half_size_m(const Terrain& terrain, const LidarModel& lidar,
                                const Footprint& footprint, const LocalFrame& frame,
                                double angle_rad) {
  const BeamSampler beam(lidar, footprint.beam_ecef);
  double reach_m = footprint.range_m * angle_rad;
  for (int k = 0; k < 8; ++k) {
    const Vec3 direction = beam.direction_at(angle_rad, k * std::numbers::pi / 4.0);
    if (const auto hit = intersect_terrain(terrain, footprint.spacecraft_ecef, direction)) {
      const Vec3 local = frame.local_from_ecef(*hit);
      reach_m = std::max(reach_m, std::hypot(local[0], local[1]));
    }
  }
  return patch_half_size_m(reach_m);
}

bool beam_on_terrain_data(const Terrain& terrain, const LidarModel& lidar,
                          const Footprint& footprint) {
  const double data_radius_m = 3.0 * footprint.range_m * lidar.beam_sigma_rad() /
                               std::cos(footprint.off_nadir_deg * std::numbers::pi / 180.0);
  return footprint.on_terrain && terrain.has_data(LocalFrame(footprint.ground), data_radius_m);
}

std::vector<std::array<double, 2>> beam_outline(const Scene& scene, const LidarModel& lidar,
                                                const ShotGeometry& geometry,
                                                const LocalFrame& frame) {
  const BeamSampler beam(lidar, geometry.axis);
  const double angle_rad = std::min(2.0 * lidar.beam_sigma_rad(), 0.5 * lidar.sensor().ifov_rad);
  const double start_height_m = scene.top_m() + 1.0;
  std::vector<std::array<double, 2>> ring;
  for (int k = 0; k < outline_vertices; ++k) {
    const Vec3 direction =
        beam.direction_at(angle_rad, 2.0 * std::numbers::pi * k / outline_vertices);
    const double start_m = (geometry.sensor_m[2] - start_height_m) / -direction[2];
    const Vec3 origin = geometry.sensor_m + start_m * direction;
    const SurfaceHit hit = scene.intersect(origin, direction, 1.0e5);
    if (hit.kind == SurfaceKind::none) continue;
    const Geodetic point = frame.to_geodetic(origin + hit.distance_m * direction);
    ring.push_back({point.lon_deg, point.lat_deg});
  }
  if (ring.size() < 3) return {};
  double twice_area = 0.0;
  for (std::size_t i = 0; i < ring.size(); ++i) {
    const auto& a = ring[i];
    const auto& b = ring[(i + 1) % ring.size()];
    twice_area += a[0] * b[1] - b[0] * a[1];
  }
  if (twice_area < 0.0) std::reverse(ring.begin(), ring.end());
  ring.push_back(ring.front());
  return ring;
}

}  // namespace glaswave
