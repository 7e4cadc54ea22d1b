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

}  // namespace glaswave
