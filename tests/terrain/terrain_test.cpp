// The plane terrain, ground meshes and beam-weighted plane fits, against hand geometry.
#include "terrain/terrain.hpp"

#include <gtest/gtest.h>

#include <GeographicLib/Geodesic.hpp>
#include <cmath>
#include <limits>
#include <numbers>

#include "terrain/ground_mesh.hpp"
#include "terrain/local_frame.hpp"

namespace glaswave {
namespace {

constexpr double deg = std::numbers::pi / 180.0;

TEST(PlaneTerrain, FallsTowardItsAspect) {
  const PlaneTerrain plane({45.0, 7.0, 300.0, 10.0, 90.0});
  EXPECT_NEAR(plane.height_m(45.0, 7.0), 300.0, 1e-9);
  // 100 m east (downslope, the plane faces east) and 100 m north (level) along geodesics.
  double lat = 0, lon = 0;
  GeographicLib::Geodesic::WGS84().Direct(45.0, 7.0, 90.0, 100.0, lat, lon);
  EXPECT_NEAR(plane.height_m(lat, lon), 300.0 - 100.0 * std::tan(10.0 * deg), 1e-3);
  GeographicLib::Geodesic::WGS84().Direct(45.0, 7.0, 0.0, 100.0, lat, lon);
  EXPECT_NEAR(plane.height_m(lat, lon), 300.0, 1e-3);
}

TEST(LocalFrame, RoundTripsAndAxesAreOrthonormal) {
  const LocalFrame frame({34.3, -118.2, 1200.0});
  const Vec3 local{120.0, -35.0, 8.0};
  const Vec3 back = frame.local_from_ecef(frame.ecef_from_local(local));
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(back[i], local[i], 1e-6);
  const Geodetic p = frame.to_geodetic(local);
  const Vec3 again = frame.to_local(p);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(again[i], local[i], 1e-6);
  const auto axes = enu_axes(34.3, -118.2);
  EXPECT_NEAR(dot(axes[0], axes[1]), 0.0, 1e-15);
  EXPECT_NEAR(dot(axes[1], axes[2]), 0.0, 1e-15);
  EXPECT_NEAR(norm(cross(axes[0], axes[1]) - axes[2]), 0.0, 1e-15);  // right-handed
}

TEST(GroundMesh, LiesOnThePlaneInTheFootprintFrame) {
  const PlaneTerrain plane({10.0, 20.0, 50.0, 20.0, 135.0});
  const LocalFrame frame({10.0, 20.0, 50.0});
  const GroundMesh mesh = build_ground_mesh(plane, frame, 100.0, 25.0);
  EXPECT_EQ(mesh.vertices_m.size(), 3u * 9 * 9);
  EXPECT_EQ(mesh.triangles.size(), 3u * 2 * 8 * 8);
  // Every node on z = -tan(S) (x sin A + y cos A), less the Earth's curvature (x^2 + y^2) / 2R:
  // the plane's heights are above the ellipsoid, the frame is a tangent plane.
  const double gradient = std::tan(20.0 * deg);
  for (std::size_t v = 0; v < mesh.vertices_m.size(); v += 3) {
    const double x = mesh.vertices_m[v], y = mesh.vertices_m[v + 1], z = mesh.vertices_m[v + 2];
    const double curvature_m = (x * x + y * y) / (2.0 * 6.36e6);
    // 1 mm: the local verticals tilt by distance / R from the frame's up, moving high nodes.
    EXPECT_NEAR(
        z, -gradient * (x * std::sin(135.0 * deg) + y * std::cos(135.0 * deg)) - curvature_m, 1e-3);
  }
}

// A terrain with no data east of its origin.
class HalfTerrain final : public Terrain {
 public:
  double height_m(double, double lon_deg) const override {
    return lon_deg > 20.0 ? std::numeric_limits<double>::quiet_NaN() : 0.0;
  }
  double detail_m() const override { return 10.0; }
};

TEST(GroundMesh, LeavesOutCellsOverMissingData) {
  const HalfTerrain terrain;
  const LocalFrame frame({0.0, 20.0, 0.0});
  const GroundMesh mesh = build_ground_mesh(terrain, frame, 50.0, 10.0);
  // 10 x 10 cells; columns east of the origin (x > 0) have a missing corner.
  EXPECT_EQ(mesh.triangles.size(), 3u * 2 * 5 * 10);
}

TEST(SurfaceOrientation, RecoversSlopeAndAspectOfPlanes) {
  for (double aspect_deg : {0.0, 45.0, 200.0, 315.0}) {
    const PlaneTerrain plane({-33.0, 151.0, 0.0, 25.0, aspect_deg});
    const LocalFrame frame({-33.0, 151.0, 0.0});
    const SurfaceOrientation fit = fit_surface_orientation(plane, frame, 16.5);
    EXPECT_NEAR(fit.slope_deg, 25.0, 0.01) << aspect_deg;
    // Aspect is an angle: 359.99999 is 0 to within 1e-5 degree.
    EXPECT_NEAR(std::remainder(fit.aspect_deg - aspect_deg, 360.0), 0.0, 0.01) << aspect_deg;
  }
}

}  // namespace
}  // namespace glaswave
