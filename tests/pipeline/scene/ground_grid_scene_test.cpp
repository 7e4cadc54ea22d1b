// The roughness's lattice handed to Embree as grids: a ray meets the same surface as on the
// grids' own triangles (triangulate_grid's diagonal kept), and the rest of the ground as before.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "pipeline/scene/scene.hpp"
#include "terrain/roughness.hpp"
#include "terrain/terrain.hpp"

namespace glaswave {
namespace {

TEST(GroundGrids, RaysMeetTheSameSurfaceAsOnTheGridsTriangles) {
  // Strong relief on a coarse lattice (0.4 m RMS, a node every 0.5 m), so that the other
  // diagonal would put a cell's middle centimetres off; three squares, two overlapping, on a
  // 15 degree plane.
  const RoughnessField field({0.4, 1.5}, 23);
  const PlaneTerrain plane({45.0, 7.0, 600.0, 15.0, 250.0});
  const LocalFrame frame({45.0, 7.0, 600.0});
  const GroundMesh base = build_ground_mesh(plane, frame, 40.0, 1.0e9);
  const GroundMesh mesh =
      field.roughen(base, frame, {{-12.0, 0.0, 10.0}, {0.0, 4.0, 10.0}, {20.0, -10.0, 6.0}}, 1.0e9);
  ASSERT_FALSE(mesh.grids.empty());
  const GroundMesh triangles = mesh.triangulated();

  const RayDevice device;
  const Scene on_grids(device, mesh), on_triangles(device, triangles);
  std::mt19937_64 bits(5);
  std::uniform_real_distribution<double> across(-25.0, 25.0), tilt(-0.1, 0.1);
  int hits = 0;
  double worst_m = 0.0, worst_normal = 0.0;
  for (int k = 0; k < 20000; ++k) {
    const Vec3 origin{across(bits), across(bits), 60.0};
    const Vec3 direction = normalized(Vec3{tilt(bits), tilt(bits), -1.0});
    const SurfaceHit a = on_grids.ground_hit(origin, direction, 200.0);
    const SurfaceHit b = on_triangles.ground_hit(origin, direction, 200.0);
    ASSERT_EQ(a.kind, b.kind) << "at " << origin[0] << ", " << origin[1];
    if (a.kind == SurfaceKind::none) continue;
    EXPECT_EQ(a.kind, SurfaceKind::ground);
    ++hits;
    worst_m = std::max(worst_m, std::abs(a.distance_m - b.distance_m));
    worst_normal = std::max(worst_normal, norm(a.normal - b.normal));
  }
  EXPECT_EQ(hits, 20000);  // every ray ends on the 40 m square
  // Float rounding alone: a few units in the last place of 60 m.
  EXPECT_LT(worst_m, 2e-5);
  EXPECT_LT(worst_normal, 1e-4);
}

}  // namespace
}  // namespace glaswave
