// The plane terrain, ground meshes and beam-weighted plane fits, against hand geometry.
#include "terrain/terrain.hpp"

#include <gtest/gtest.h>

#include <GeographicLib/Geodesic.hpp>
#include <algorithm>
#include <array>
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

// A plane answers has_data without sampling: what the samples Terrain::has_data takes would say,
// over a footprint anywhere on the globe, poles and the antimeridian included, and 50 km wide.
TEST(PlaneTerrain, HasDataEverywhereAsItsSamplesSay) {
  const PlaneTerrain plane({45.0, 7.0, 300.0, 20.0, 90.0});
  for (const double lat_deg : {-90.0, -60.0, 0.0, 45.0, 89.9})
    for (const double lon_deg : {-180.0, 7.0, 179.9}) {
      const LocalFrame frame({lat_deg, lon_deg, 100.0});
      for (const double radius_m : {10.0, 50000.0}) {
        EXPECT_TRUE(plane.has_data(frame, radius_m));
        EXPECT_TRUE(plane.Terrain::has_data(frame, radius_m)) << lat_deg << " " << lon_deg;
      }
    }
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

// Heights k x^3, x east of an origin: a surface whose beam-weighted plane depends on the
// weights. Over the fit's square of +-3.5 sigma, with Gaussian weights of RMS width sigma, the
// symmetric weights leave the plane's east gradient k sigma^2 I4 / I2, the truncated moments
// I_n = integral of t^n exp(-t^2 / 2) over [-3.5, 3.5], by parts I4 = 3 I2 - 2 a^3 exp(-a^2/2)
// and I2 = sqrt(2 pi) erf(a / sqrt 2) - 2 a exp(-a^2 / 2): 2.925 sigma^2 k, where untruncated
// weights would give 3 and uniform ones 7.35.
class CubicTerrain final : public Terrain {
 public:
  CubicTerrain(const Geodetic& origin, double k_per_m2) : origin_(origin), k_per_m2_(k_per_m2) {}
  double height_m(double lat_deg, double lon_deg) const override {
    const double x_m = origin_.to_local({lat_deg, lon_deg, 0.0})[0];
    return k_per_m2_ * x_m * x_m * x_m;
  }
  // The mesh interpolates the cubic linearly between nodes: on 1 m cells that moves the fit by
  // 0.67 h^2 / (2.925 sigma^2) = 0.23 %, on 0.25 m cells by 0.015 %.
  double detail_m() const override { return 0.25; }

 private:
  LocalFrame origin_;
  double k_per_m2_;
};

TEST(SurfaceOrientation, WeighsTheSurfaceByTheBeamsGaussian) {
  const double sigma_m = 10.0, a = 3.5;
  const double tail = std::exp(-0.5 * a * a);
  const double i2 =
      std::sqrt(2.0 * std::numbers::pi) * std::erf(a / std::sqrt(2.0)) - 2.0 * a * tail;
  const double i4 = 3.0 * i2 - 2.0 * a * a * a * tail;
  const double k_per_m2 = 0.2 / (sigma_m * sigma_m * 3.0);
  const Geodetic origin{46.0, 8.0, 0.0};
  const CubicTerrain terrain(origin, k_per_m2);
  const SurfaceOrientation fit = fit_surface_orientation(terrain, LocalFrame(origin), sigma_m);
  const double gradient = k_per_m2 * sigma_m * sigma_m * i4 / i2;  // 0.195
  EXPECT_NEAR(std::tan(fit.slope_deg * deg), gradient, 1e-3 * gradient);
  EXPECT_NEAR(fit.aspect_deg, 270.0, 0.05);  // rising eastward, it faces west
}

// The triangles of a list, each in its own vertex order, sorted: the surface, and which
// diagonal cuts each cell, whatever order the list has them in.
std::vector<std::array<std::uint32_t, 3>> triangle_set(const std::vector<std::uint32_t>& list) {
  std::vector<std::array<std::uint32_t, 3>> set;
  for (std::size_t t = 0; t < list.size(); t += 3)
    set.push_back({list[t], list[t + 1], list[t + 2]});
  std::sort(set.begin(), set.end());
  return set;
}

// mesh_grid_cells hands over the wanted cells whose four nodes have vertices as grids and the
// rest as triangles: together triangulate_grid's triangles of the wanted cells, the same vertex
// order, no cell twice; a row longer than Embree's limit goes in several grids.
TEST(MeshGridCells, AreTriangulateGridsTrianglesOfTheWantedCells) {
  const int ni = 9, nj = 7;
  std::vector<std::uint32_t> node_vertex(ni * nj);
  for (std::size_t n = 0; n < node_vertex.size(); ++n)
    node_vertex[n] = static_cast<std::uint32_t>(n);
  node_vertex[3 * ni + 4] = no_vertex;  // a node without data
  std::vector<char> cell_in((ni - 1) * (nj - 1), 1);
  for (int i = 0; i < 3; ++i) cell_in[5 * (ni - 1) + i] = 0;  // cells not wanted
  cell_in[0] = 0;
  GroundMesh mesh;
  mesh_grid_cells(ni, nj, node_vertex, cell_in, mesh);
  EXPECT_GE(mesh.grids.size(), 2u);
  // The cells about the missing node: a triangle each where it is off their diagonal.
  EXPECT_EQ(mesh.triangles.size(), 6u);
  std::vector<std::uint32_t> wanted;
  std::vector<std::uint32_t> one_cell(4);
  for (int j = 0; j + 1 < nj; ++j)
    for (int i = 0; i + 1 < ni; ++i) {
      if (!cell_in[j * (ni - 1) + i]) continue;
      one_cell = {node_vertex[j * ni + i], node_vertex[j * ni + i + 1],
                  node_vertex[(j + 1) * ni + i], node_vertex[(j + 1) * ni + i + 1]};
      triangulate_grid(2, 2, one_cell, wanted);
    }
  EXPECT_EQ(triangle_set(mesh.triangulated().triangles), triangle_set(wanted));

  const int long_ni = max_grid_nodes + 100;
  std::vector<std::uint32_t> row(2 * static_cast<std::size_t>(long_ni));
  for (std::size_t n = 0; n < row.size(); ++n) row[n] = static_cast<std::uint32_t>(n);
  GroundMesh long_mesh;
  mesh_grid_cells(long_ni, 2, row, {}, long_mesh);
  ASSERT_EQ(long_mesh.grids.size(), 2u);
  for (const MeshGrid& grid : long_mesh.grids) EXPECT_LE(grid.width, max_grid_nodes);
  std::vector<std::uint32_t> all;
  triangulate_grid(long_ni, 2, row, all);
  EXPECT_EQ(triangle_set(long_mesh.triangulated().triangles), triangle_set(all));
}

}  // namespace
}  // namespace glaswave
