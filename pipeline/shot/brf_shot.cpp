// The BRF's scene, built as a shot's is, and its trace.
#include "pipeline/shot/brf_shot.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "pipeline/shot/footprint_geometry.hpp"

namespace glaswave {

BrfScene build_brf_scene(const ShotSimulator& simulator, const Footprint& footprint,
                         double tile_half_size_m, bool periodic) {
  const SceneBuilder& scenes = simulator.scenes();
  const LocalFrame frame(footprint.ground);
  BrfScene brf;
  brf.tile.half_size_m = tile_half_size_m;
  brf.tile.periodic = periodic;
  const SurfaceOrientation orientation = fit_surface_orientation(
      scenes.terrain(), frame, footprint.range_m * simulator.lidar().beam_sigma_rad());
  // Across a periodic plane's tile the ground climbs as the plane does (a DEM's tile is lit and
  // seen through its level top).
  const double deg = std::numbers::pi / 180.0;
  const double fall = periodic ? std::tan(orientation.slope_deg * deg) : 0.0;
  brf.tile.ground_slope_x = -fall * std::sin(orientation.aspect_deg * deg);
  brf.tile.ground_slope_y = -fall * std::cos(orientation.aspect_deg * deg);
  const double half_size_m = brf_scene_half_size_m(tile_half_size_m, periodic);
  brf.built = scenes.build(frame, orientation, half_size_m, half_size_m);
  return brf;
}

std::optional<std::array<double, 2>> tile_off_terrain(const Terrain& terrain,
                                                      const LocalFrame& frame,
                                                      double tile_half_size_m) {
  const double side_m = 2.0 * tile_half_size_m;
  constexpr int most_steps = 256;
  const int steps = static_cast<int>(
      std::clamp(std::ceil(side_m / std::max(terrain.detail_m(), 1e-3)), 1.0, double{most_steps}));
  for (int j = 0; j <= steps; ++j)
    for (int i = 0; i <= steps; ++i) {
      const double x = -tile_half_size_m + side_m * i / steps,
                   y = -tile_half_size_m + side_m * j / steps;
      const Geodetic p = frame.to_geodetic({x, y, 0.0});
      if (!std::isfinite(terrain.height_m(p.lat_deg, p.lon_deg)))
        return std::array<double, 2>{x, y};
    }
  return std::nullopt;
}

BrfResult trace_brf(const BrfScene& scene, const BrfOptions& options, const BrfProgress& progress) {
  return simulate_brf(*scene.built.scene, scene.built.optics, scene.tile, options, progress);
}

}  // namespace glaswave
