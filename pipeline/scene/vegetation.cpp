// Crowns, trunks and layers placed in a shot's frame.
#include "pipeline/scene/vegetation.hpp"

#include <cmath>
#include <limits>
#include <numbers>

namespace glaswave {
namespace {

constexpr int trunk_sides = 8;

// A vertical prism of `trunk_sides` faces from the ground to the crown base.
void add_trunk(Vegetation& vegetation, const Vec3& foot, double top_m, double radius_m,
               int material) {
  GroundMesh& mesh = vegetation.trunks;
  const auto first = static_cast<std::uint32_t>(mesh.vertices_m.size() / 3);
  for (int k = 0; k < trunk_sides; ++k) {
    const double angle = 2.0 * std::numbers::pi * k / trunk_sides;
    const double x = foot[0] + radius_m * std::cos(angle), y = foot[1] + radius_m * std::sin(angle);
    // The foot goes a little below the ground so that no gap shows on slopes.
    for (double z : {foot[2] - radius_m, top_m}) {
      mesh.vertices_m.insert(mesh.vertices_m.end(),
                             {static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)});
    }
  }
  for (std::uint32_t k = 0; k < trunk_sides; ++k) {
    const std::uint32_t a = first + 2 * k, b = a + 1, c = first + 2 * ((k + 1) % trunk_sides),
                        d = c + 1;
    mesh.triangles.insert(mesh.triangles.end(), {a, c, d, a, d, b});
    vegetation.trunk_materials.insert(vegetation.trunk_materials.end(), {material, material});
  }
  mesh.max_height_m = std::max(mesh.max_height_m, top_m);
}

}  // namespace

Vegetation build_vegetation(const Forest& forest, const Terrain& terrain, const LocalFrame& frame,
                            double half_size_m, const SurfaceOrientation& ground) {
  Vegetation vegetation;
  vegetation.trunks.max_height_m = -std::numeric_limits<double>::infinity();
  const CanopySettings& scene_canopy = forest.canopy(0);
  if (scene_canopy.crown_shape == CrownShape::layer) {
    if (scene_canopy.pai <= 0.0) return vegetation;
    const double deg = std::numbers::pi / 180.0;
    const double fall = std::tan(ground.slope_deg * deg);
    TurbidLayer layer;
    layer.ground_slope_x = -fall * std::sin(ground.aspect_deg * deg);
    layer.ground_slope_y = -fall * std::cos(ground.aspect_deg * deg);
    layer.bottom_m = scene_canopy.crown_base_m[0];
    layer.top_m = scene_canopy.crown_base_m[0] + 2.0 * scene_canopy.crown_half_height_m;
    layer.area_density_m2_m3 = forest.area_density_m2_m3(0);
    vegetation.layer = layer;
    return vegetation;
  }
  const Geodetic centre = frame.origin();
  double widest_m = 0.0;
  for (std::size_t k = 0; k < forest.kinds(); ++k)
    widest_m = std::max(widest_m, forest.canopy(k).crown_radius_m);
  for (const Tree& tree :
       forest.trees_near(centre.lat_deg, centre.lon_deg, half_size_m * std::sqrt(2.0) + widest_m)) {
    const CanopySettings& canopy = forest.canopy(tree.kind);
    if (canopy.pai <= 0.0) continue;
    const double ground_m = terrain.height_m(tree.lat_deg, tree.lon_deg);
    if (!std::isfinite(ground_m)) continue;
    const Vec3 foot = frame.to_local({tree.lat_deg, tree.lon_deg, ground_m});
    const double reach_m = half_size_m + tree.crown_radius_m;
    if (std::abs(foot[0]) > reach_m || std::abs(foot[1]) > reach_m) continue;
    Crown crown;
    crown.shape = canopy.crown_shape;
    crown.base_m = foot + Vec3{0.0, 0.0, tree.crown_base_m};
    crown.radius_m = tree.crown_radius_m;
    crown.half_height_m = tree.crown_half_height_m;
    crown.area_density_m2_m3 = forest.area_density_m2_m3(tree.kind);
    crown.material = tree.kind;
    vegetation.crowns.push_back(crown);
    if (canopy.dbh_m > 0.0 && tree.crown_base_m > 0.0)
      add_trunk(vegetation, foot, crown.base_m[2], 0.5 * canopy.dbh_m, tree.kind);
  }
  return vegetation;
}

VegetationTruth measure_vegetation(const Scene& scene, double sigma_m) {
  VegetationTruth truth;
  if (!scene.has_volumes()) return truth;
  constexpr int half_nodes = 20;  // a 41 x 41 grid out to 3 sigma
  const double step_m = 3.0 * sigma_m / half_nodes;
  const double start_m = scene.top_m() + 1.0;
  const Vec3 down{0.0, 0.0, -1.0};
  std::vector<VolumeSpan> spans;
  double weights = 0.0;
  for (int j = -half_nodes; j <= half_nodes; ++j) {
    for (int i = -half_nodes; i <= half_nodes; ++i) {
      const double x = i * step_m, y = j * step_m, r_sq = x * x + y * y;
      const Vec3 origin{x, y, start_m};
      const SurfaceHit ground = scene.intersect(origin, down, 1.0e5);
      if (ground.kind == SurfaceKind::none) continue;
      scene.volume_spans(origin, down, ground.distance_m, spans);
      double plant_area = 0.0, first_m = ground.distance_m;
      for (const VolumeSpan& span : spans) {
        plant_area += span.area_density_m2_m3 * (span.end_m - span.start_m);
        first_m = std::min(first_m, span.start_m);
      }
      const double weight = std::exp(-r_sq / (2.0 * sigma_m * sigma_m));
      weights += weight;
      truth.pai += weight * plant_area;
      truth.cover += spans.empty() ? 0.0 : weight;
      if (r_sq <= 4.0 * sigma_m * sigma_m)
        truth.canopy_height_m = std::max(truth.canopy_height_m, ground.distance_m - first_m);
    }
  }
  if (weights > 0.0) {
    truth.pai /= weights;
    truth.cover /= weights;
  }
  return truth;
}

}  // namespace glaswave
