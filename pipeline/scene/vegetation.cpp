// Crowns, trunks and layers placed in a shot's frame.
#include "pipeline/scene/vegetation.hpp"

#include <cmath>
#include <limits>
#include <numbers>

namespace glaswave {
namespace {

constexpr int trunk_sides = 8;

// A vertical prism of `trunk_sides` faces from the ground to the crown base.
void add_trunk(GroundMesh& mesh, const Vec3& foot, double top_m, double radius_m) {
  const auto first = static_cast<std::uint32_t>(mesh.vertices_m.size() / 3);
  for (int k = 0; k < trunk_sides; ++k) {
    const double angle = 2.0 * std::numbers::pi * k / trunk_sides;
    const double x = foot[0] + radius_m * std::cos(angle), y = foot[1] + radius_m * std::sin(angle);
    // The foot goes a little below the ground so that no gap shows on slopes.
    for (double z : {foot[2] - radius_m, top_m}) {
      mesh.vertices_m.insert(mesh.vertices_m.end(), {static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)});
    }
  }
  for (std::uint32_t k = 0; k < trunk_sides; ++k) {
    const std::uint32_t a = first + 2 * k, b = a + 1, c = first + 2 * ((k + 1) % trunk_sides), d = c + 1;
    mesh.triangles.insert(mesh.triangles.end(), {a, c, d, a, d, b});
  }
  mesh.max_height_m = std::max(mesh.max_height_m, top_m);
}

}  // namespace

Vegetation build_vegetation(const CanopySettings& canopy, const Stand& stand, const Terrain& terrain,
                            const LocalFrame& frame, double half_size_m, const SurfaceOrientation& ground) {
  Vegetation vegetation;
  vegetation.trunks.max_height_m = -std::numeric_limits<double>::infinity();
  if (canopy.pai <= 0.0) return vegetation;
  if (canopy.crown_shape == CrownShape::layer) {
    const double deg = std::numbers::pi / 180.0;
    const double fall = std::tan(ground.slope_deg * deg);
    TurbidLayer layer;
    layer.ground_slope_x = -fall * std::sin(ground.aspect_deg * deg);
    layer.ground_slope_y = -fall * std::cos(ground.aspect_deg * deg);
    layer.bottom_m = canopy.crown_base_m[0];
    layer.top_m = canopy.crown_base_m[0] + 2.0 * canopy.crown_half_height_m;
    layer.area_density_m2_m3 = canopy.pai / (2.0 * canopy.crown_half_height_m);
    vegetation.layer = layer;
    return vegetation;
  }
  const Geodetic centre = frame.origin();
  for (const Tree& tree : stand.trees_near(centre.lat_deg, centre.lon_deg, half_size_m * std::sqrt(2.0) + canopy.crown_radius_m)) {
    const double ground_m = terrain.height_m(tree.lat_deg, tree.lon_deg);
    if (!std::isfinite(ground_m)) continue;
    const Vec3 foot = frame.to_local({tree.lat_deg, tree.lon_deg, ground_m});
    if (std::abs(foot[0]) > half_size_m + canopy.crown_radius_m || std::abs(foot[1]) > half_size_m + canopy.crown_radius_m)
      continue;
    Crown crown;
    crown.shape = canopy.crown_shape;
    crown.base_m = foot + Vec3{0.0, 0.0, tree.crown_base_m};
    crown.radius_m = canopy.crown_radius_m;
    crown.half_height_m = canopy.crown_half_height_m;
    crown.area_density_m2_m3 = stand.area_density_m2_m3();
    vegetation.crowns.push_back(crown);
    if (canopy.dbh_m > 0.0 && tree.crown_base_m > 0.0) add_trunk(vegetation.trunks, foot, crown.base_m[2], 0.5 * canopy.dbh_m);
  }
  return vegetation;
}

}  // namespace glaswave
