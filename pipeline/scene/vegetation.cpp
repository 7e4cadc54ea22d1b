// The footprint's truth, measured along vertical lines through the scene.
#include "pipeline/scene/vegetation.hpp"

#include <cmath>
#include <limits>
#include <numbers>

namespace glaswave {

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

VegetationTruth measure_facets(const Scene& scene, double sigma_m) {
  VegetationTruth truth;
  if (scene.facets().empty()) return truth;
  const double two_sigma_sq = 2.0 * sigma_m * sigma_m;
  for (const FacetInstance& tree : scene.facets()) {
    const double c = std::cos(tree.rotation_rad), s = std::sin(tree.rotation_rad);
    const double scale_sq = tree.scale * tree.scale;
    for (const FacetModel::AreaCell& cell : tree.model->area_cells()) {
      const double x = tree.foot_m[0] + tree.scale * (c * cell.x_m + s * cell.y_m);
      const double y = tree.foot_m[1] + tree.scale * (-s * cell.x_m + c * cell.y_m);
      truth.pai += cell.area_m2 * scale_sq * std::exp(-(x * x + y * y) / two_sigma_sq);
    }
  }
  truth.pai /= std::numbers::pi * two_sigma_sq;
  constexpr int half_nodes = 20;  // a 41 x 41 grid out to 3 sigma, as for the volumes
  constexpr int max_crossings = 100000;
  const double step_m = 3.0 * sigma_m / half_nodes;
  const double start_m = scene.top_m() + 1.0;
  const Vec3 down{0.0, 0.0, -1.0};
  double weights = 0.0;
  for (int j = -half_nodes; j <= half_nodes; ++j) {
    for (int i = -half_nodes; i <= half_nodes; ++i) {
      const double x = i * step_m, y = j * step_m, r_sq = x * x + y * y;
      const Vec3 origin{x, y, start_m};
      const SurfaceHit first = scene.intersect(origin, down, 1.0e5);
      if (first.kind == SurfaceKind::none) continue;
      const double weight = std::exp(-r_sq / (2.0 * sigma_m * sigma_m));
      weights += weight;
      if (first.kind == SurfaceKind::ground) continue;
      truth.cover += weight;
      if (r_sq > 4.0 * sigma_m * sigma_m) continue;
      // Down through the facets to the ground, for the height of the first above it.
      SurfaceHit below = first;
      for (int k = 0; k < max_crossings && below.kind != SurfaceKind::none &&
                      below.kind != SurfaceKind::ground;
           ++k)
        below = scene.intersect(origin, down, 1.0e5, below.distance_m + 1e-4);
      if (below.kind == SurfaceKind::ground)
        truth.canopy_height_m =
            std::max(truth.canopy_height_m, below.distance_m - first.distance_m);
    }
  }
  if (weights > 0.0) truth.cover /= weights;
  return truth;
}

}  // namespace glaswave
