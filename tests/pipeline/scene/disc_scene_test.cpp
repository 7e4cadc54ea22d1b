// Disc leaves in a scene (Embree's oriented disc points, instanced): each hit against the closed
// form of a ray and a disc, t = (c - o).n / (d.n) and |o + t d - c| <= r, from either side, in a
// turned, scaled and lifted instance; and the model's bounds and area.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "pipeline/scene/facet_model.hpp"
#include "pipeline/scene/scene.hpp"

namespace glaswave {
namespace {

TEST(DiscScene, HitsFollowTheRayPlaneClosedFormFromBothSides) {
  // One disc of radius 0.5 m at (1, 2, 3) in its model, its normal tilted 30 degrees from up
  // toward +x; an instance turned 90 degrees (the model's +y to the east), scaled 2 and lifted
  // to (10, -5, 4): in the scene the disc's centre is (10 + 2*2, -5 - 2*1, 4 + 2*3) = (14, -7, 10),
  // its radius 1 m, its normal (0, -sin 30, cos 30) (the model's +x turned to the south).
  const double tilt = std::numbers::pi / 6.0;
  DiscLeaves discs;
  discs.discs_m = {1.0f, 2.0f, 3.0f, 0.5f};
  discs.normals = {static_cast<float>(std::sin(tilt)), 0.0f, static_cast<float>(std::cos(tilt))};
  auto model = std::make_shared<const FacetModel>(std::move(discs), 0);
  EXPECT_NEAR(model->area_m2(), std::numbers::pi * 0.25, 1e-12);
  EXPECT_NEAR(model->top_m(), 3.0 + 0.5 * std::sin(tilt), 1e-6);
  EXPECT_NEAR(model->bottom_m(), 3.0 - 0.5 * std::sin(tilt), 1e-6);
  EXPECT_NEAR(model->reach_m(), std::hypot(1.0, 2.0) + 0.5, 1e-6);
  Vegetation vegetation;
  vegetation.facets = {{model, {10.0, -5.0, 4.0}, std::numbers::pi / 2.0, 2.0}};
  vegetation.leaf_materials = {1};
  const RayDevice device;
  const Scene scene(device, GroundMesh{}, vegetation);
  const Vec3 centre{14.0, -7.0, 10.0};
  const Vec3 normal{0.0, -std::sin(tilt), std::cos(tilt)};
  const double radius = 1.0;

  std::mt19937_64 bits(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int hits = 0, from_below = 0;
  for (int k = 0; k < 4000; ++k) {
    // Rays from above and below aimed near the disc, at up to 60 degrees from the vertical.
    const double side = k % 2 == 0 ? 1.0 : -1.0;
    const Vec3 target = centre + Vec3{1.5 * u(bits), 1.5 * u(bits), 0.3 * u(bits)};
    const Vec3 direction = normalized(Vec3{0.6 * u(bits), 0.6 * u(bits), -side});
    const Vec3 origin = target - 20.0 * direction;
    const double t = dot(centre - origin, normal) / dot(direction, normal);
    const double miss = norm(origin + t * direction - centre) - radius;
    const SurfaceHit hit = scene.intersect(origin, direction, 100.0);
    if (std::abs(miss) < 1e-4) continue;  // the rim, where float rounding decides
    if (miss > 0.0) {
      EXPECT_EQ(hit.kind, SurfaceKind::none) << k;
      continue;
    }
    ++hits;
    from_below += side < 0.0;
    ASSERT_EQ(hit.kind, SurfaceKind::leaf) << k;
    EXPECT_EQ(hit.material, 0);
    EXPECT_NEAR(hit.distance_m, t, 2e-5) << k;
    // The normal on the side the ray came from.
    const Vec3 facing = dot(normal, direction) < 0.0 ? normal : -1.0 * normal;
    EXPECT_NEAR(norm(hit.normal - facing), 0.0, 1e-5) << k;
  }
  RecordProperty("hits", hits);
  EXPECT_GT(hits, 1000);
  EXPECT_GT(from_below, 500);
  EXPECT_NEAR(scene.top_m(), 10.0 + 2.0 * 0.5 * std::sin(tilt), 1e-5);
}

}  // namespace
}  // namespace glaswave
