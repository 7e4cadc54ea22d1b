// The roughness field: its RMS and correlation over a large area against the settings, the same
// relief for overlapping footprints, and meshes that carry it without gaps or double cover.
#include "terrain/roughness.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "terrain/ground_mesh.hpp"

namespace glaswave {
namespace {

// A random geodetic point within `half_m` of a frame's origin.
Geodetic random_point(const LocalFrame& frame, double half_m, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-half_m, half_m);
  return frame.to_geodetic({u(rng), u(rng), 0.0});
}

// Over 3 km x 3 km (a million correlation cells) the field's RMS is the setting: the spread of
// a 40 000-point estimate is 0.35 %, so 1.5 % cannot be missed by a wrong normalisation (the
// lattice nodes alone have an RMS 3 % higher than their piecewise-linear surface).
TEST(Roughness, FieldRmsOverALargeAreaIsTheSetting) {
  const RoughnessField field({0.5, 2.0}, 3);
  EXPECT_NEAR(field.spacing_m(), 2.0 / 3.0, 1e-12);
  const LocalFrame frame({34.3, -118.2, 0.0});
  std::mt19937_64 rng(1);
  double sum = 0.0, sum_sq = 0.0;
  constexpr int samples = 40000;
  for (int k = 0; k < samples; ++k) {
    const Geodetic p = random_point(frame, 1500.0, rng);
    const double h = field.height_m(p.lat_deg, p.lon_deg);
    sum += h;
    sum_sq += h * h;
  }
  const double mean = sum / samples, rms = std::sqrt(sum_sq / samples);
  EXPECT_NEAR(mean, 0.0, 0.01);
  EXPECT_NEAR(rms / 0.5, 1.0, 0.015);
  // Another seed, another field; no roughness, no field.
  const RoughnessField other({0.5, 2.0}, 4);
  EXPECT_NE(field.height_m(34.3, -118.2), other.height_m(34.3, -118.2));
  EXPECT_FALSE(RoughnessField({0.0, 2.0}, 3).enabled());
}

// The coarser lattices (a node every L/2 and every L) keep the setting's RMS over a large area,
// each with its own noise.
TEST(Roughness, CoarserLatticesKeepTheRms) {
  const RoughnessField field({0.45, 0.5}, 3);
  const LocalFrame frame({34.3, -118.2, 0.0});
  for (int level : {1, 2}) {
    std::mt19937_64 rng(7);
    double sum_sq = 0.0;
    constexpr int samples = 20000;  // spread 0.5 %
    for (int k = 0; k < samples; ++k) {
      const Geodetic p = random_point(frame, 750.0, rng);
      sum_sq += std::pow(field.height_m(p.lat_deg, p.lon_deg, level), 2);
    }
    EXPECT_NEAR(std::sqrt(sum_sq / samples) / 0.45, 1.0, 0.015) << "level " << level;
    EXPECT_NE(field.height_m(34.3, -118.2, level), field.height_m(34.3, -118.2, 0));
  }
}

// Correlation against the Gaussian covariance exp(-r^2 / L^2): 1/e at one correlation length
// (the piecewise-linear surface between nodes L/3 apart lowers it a little), nothing at 3 L.
TEST(Roughness, CorrelationFallsOverTheCorrelationLength) {
  const double correlation_m = 3.0;
  const RoughnessField field({1.0, correlation_m}, 9);
  const LocalFrame frame({-20.0, 30.0, 0.0});
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> angle(0.0, 2.0 * std::numbers::pi);
  auto correlation = [&](double lag_m) {
    double product = 0.0, first_sq = 0.0, second_sq = 0.0;
    for (int k = 0; k < 8000; ++k) {
      const Geodetic p = random_point(frame, 1000.0, rng);
      const Vec3 a = frame.to_local(p);
      const double t = angle(rng);
      const Geodetic q =
          frame.to_geodetic({a[0] + lag_m * std::cos(t), a[1] + lag_m * std::sin(t), 0.0});
      const double f = field.height_m(p.lat_deg, p.lon_deg),
                   g = field.height_m(q.lat_deg, q.lon_deg);
      product += f * g;
      first_sq += f * f;
      second_sq += g * g;
    }
    return product / std::sqrt(first_sq * second_sq);
  };
  EXPECT_GT(correlation(correlation_m / 3.0), 0.85);  // exp(-1/9) = 0.89
  EXPECT_NEAR(correlation(correlation_m), std::exp(-1.0), 0.06);
  EXPECT_NEAR(correlation(3.0 * correlation_m), 0.0, 0.05);
}

// Brute force: the triangles of a mesh over a horizontal point, and the height of the first.
struct Cover {
  int count = 0;
  double z = std::numeric_limits<double>::quiet_NaN();
};
Cover cover(const GroundMesh& mesh, double x, double y, double slack) {
  Cover c;
  for (std::size_t t = 0; t < mesh.triangles.size(); t += 3) {
    const float* a = &mesh.vertices_m[3 * mesh.triangles[t]];
    const float* b = &mesh.vertices_m[3 * mesh.triangles[t + 1]];
    const float* p = &mesh.vertices_m[3 * mesh.triangles[t + 2]];
    const double d = (b[1] - p[1]) * (a[0] - p[0]) + (p[0] - b[0]) * (a[1] - p[1]);
    if (d == 0.0) continue;
    const double l0 = ((b[1] - p[1]) * (x - p[0]) + (p[0] - b[0]) * (y - p[1])) / d;
    const double l1 = ((p[1] - a[1]) * (x - p[0]) + (a[0] - p[0]) * (y - p[1])) / d;
    const double l2 = 1.0 - l0 - l1;
    if (l0 < slack || l1 < slack || l2 < slack) continue;
    if (c.count++ == 0) c.z = l0 * a[2] + l1 * b[2] + l2 * p[2];
  }
  return c;
}

// The roughened mesh: the field's relief on the base ground inside the region, the base outside,
// one surface over every point (no gap where they meet, no double cover), and the same relief
// under the same ground point whichever footprint's frame builds it.
TEST(Roughness, MeshCarriesTheFieldWithoutGapsAndAgreesBetweenFootprints) {
  const RoughnessField field({0.4, 2.0}, 17);
  const PlaneTerrain plane({45.0, 7.0, 600.0, 15.0, 250.0});
  const LocalFrame a({45.0, 7.0, 600.0});
  const Geodetic b_origin = a.to_geodetic({12.0, -7.0, 0.0});
  const LocalFrame b(
      {b_origin.lat_deg, b_origin.lon_deg, plane.height_m(b_origin.lat_deg, b_origin.lon_deg)});
  const GroundMesh mesh_a = build_ground_mesh(plane, a, 60.0, 1.0e9, &field, 30.0).triangulated();
  const GroundMesh mesh_b = build_ground_mesh(plane, b, 60.0, 1.0e9, &field, 30.0).triangulated();
  // About (2 x 30 / (2/3))^2 lattice nodes and twice as many triangles, plus the clipped base.
  EXPECT_GT(mesh_a.triangles.size() / 3, 2u * 85 * 85);
  EXPECT_LT(mesh_a.triangles.size() / 3, 2u * 100 * 100);

  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> u(-58.0, 58.0);
  double worst_field_m = 0.0, worst_overlap_m = 0.0, worst_outside_m = 0.0;
  int overlap_points = 0;
  for (int k = 0; k < 1500; ++k) {
    const double x = u(rng), y = u(rng);
    const Cover c = cover(mesh_a, x, y, -1e-7);
    ASSERT_GE(c.count, 1) << "a gap at " << x << ", " << y;
    // Strictly inside: exactly one triangle (points on shared edges are rarer than 1e-4).
    EXPECT_LE(cover(mesh_a, x, y, 1e-6).count, 1) << "double cover at " << x << ", " << y;
    const Geodetic on_mesh = a.to_geodetic({x, y, c.z});
    const double relief_m = on_mesh.h_m - plane.height_m(on_mesh.lat_deg, on_mesh.lon_deg);
    if (std::max(std::abs(x), std::abs(y)) < 17.0) {  // inside the taper
      worst_field_m = std::max(
          worst_field_m, std::abs(relief_m - field.height_m(on_mesh.lat_deg, on_mesh.lon_deg)));
      const Vec3 in_b = b.to_local(on_mesh);
      if (std::max(std::abs(in_b[0]), std::abs(in_b[1])) < 17.0) {
        const Cover cb = cover(mesh_b, in_b[0], in_b[1], -1e-7);
        ASSERT_GE(cb.count, 1);
        const Geodetic on_b = b.to_geodetic({in_b[0], in_b[1], cb.z});
        worst_overlap_m = std::max(worst_overlap_m, std::abs(on_b.h_m - on_mesh.h_m));
        ++overlap_points;
      }
    } else if (std::max(std::abs(x), std::abs(y)) > 33.0) {  // beyond the lattice: the plane
      worst_outside_m = std::max(worst_outside_m, std::abs(relief_m));
    }
  }
  EXPECT_GT(overlap_points, 30);
  EXPECT_LT(worst_field_m, 2e-3);  // the map from grid to frame is fitted to well under 1 mm
  EXPECT_LT(worst_overlap_m, 2e-3);
  EXPECT_LT(worst_outside_m, 2e-3);
}

// Several footprints' squares meshed at once (a strip's scene): two overlapping, one apart and
// one a lattice node from it. One surface over every point; the field's relief (the per-point
// convolution, height_m) deep inside any square, the same whichever squares hold a point; the
// plane beyond them all; and one square about the origin is the one-square call, bit for bit.
TEST(Roughness, SeveralSquaresCarryTheFieldWithoutGaps) {
  const RoughnessField field({0.4, 2.0}, 17);
  const PlaneTerrain plane({45.0, 7.0, 600.0, 15.0, 250.0});
  const LocalFrame frame({45.0, 7.0, 600.0});
  const GroundMesh base = build_ground_mesh(plane, frame, 60.0, 1.0e9);
  const std::vector<RoughSquare> squares = {
      {0.0, 0.0, 20.0}, {25.0, 18.0, 20.0}, {-40.0, 30.0, 10.0}, {-40.0, 8.0, 11.0}};
  const GroundMesh mesh = field.roughen(base, frame, squares, 1.0e9).triangulated();
  // Depth of (x, y) inside the deepest square holding it (negative outside them all).
  auto depth = [&](double x, double y) {
    double deepest = -1e9;
    for (const RoughSquare& s : squares)
      deepest =
          std::max(deepest, s.half_size_m - std::max(std::abs(x - s.x_m), std::abs(y - s.y_m)));
    return deepest;
  };
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-58.0, 58.0);
  double worst_field_m = 0.0, worst_outside_m = 0.0;
  int inside = 0, outside = 0;
  for (int k = 0; k < 3000; ++k) {
    const double x = u(rng), y = u(rng);
    const Cover c = cover(mesh, x, y, -1e-7);
    ASSERT_GE(c.count, 1) << "a gap at " << x << ", " << y;
    EXPECT_LE(cover(mesh, x, y, 1e-6).count, 1) << "double cover at " << x << ", " << y;
    const Geodetic on_mesh = frame.to_geodetic({x, y, c.z});
    const double relief_m = on_mesh.h_m - plane.height_m(on_mesh.lat_deg, on_mesh.lon_deg);
    // The taper is 2 correlation lengths (4 m) from a square's nodes, which reach a node
    // (0.67 m) beyond it and more where the grid turns from the frame (1.4 degrees here): 3 m
    // out, as for one square above.
    if (depth(x, y) > 5.0) {
      worst_field_m = std::max(
          worst_field_m, std::abs(relief_m - field.height_m(on_mesh.lat_deg, on_mesh.lon_deg)));
      ++inside;
    } else if (depth(x, y) < -3.0) {
      worst_outside_m = std::max(worst_outside_m, std::abs(relief_m));
      ++outside;
    }
  }
  EXPECT_GT(inside, 300);
  EXPECT_GT(outside, 1500);
  EXPECT_LT(worst_field_m, 2e-3);
  EXPECT_LT(worst_outside_m, 2e-3);

  const GroundMesh one = field.roughen(base, frame, 30.0, 1.0e9).triangulated();
  const GroundMesh same = field.roughen(base, frame, {{0.0, 0.0, 30.0}}, 1.0e9).triangulated();
  EXPECT_EQ(same.vertices_m, one.vertices_m);
  EXPECT_EQ(same.triangles, one.triangles);
}

// Ground with relief finer than the roughness lattice (ridges 3 m apart, 5 m high, in cells of
// 0.25 m) under a nearly flat roughness of 6 m correlation (lattice 2 m): the roughened mesh keeps
// the ground's own relief. Every triangle's centroid lies within 0.3 m of the ground under it (a
// 0.25 m mesh of the ridges departs from them by up to 0.17 m; a 2 m one by metres).
class Ridges final : public Terrain {
 public:
  explicit Ridges(const LocalFrame& frame) : frame_(frame) {}
  double height_m(double lat_deg, double lon_deg) const override {
    const Vec3 p = frame_.to_local({lat_deg, lon_deg, 0.0});
    return 5.0 * std::sin(2.0 * std::numbers::pi * p[0] / 3.0);
  }
  double detail_m() const override { return 0.25; }

 private:
  const LocalFrame& frame_;
};

TEST(Roughness, KeepsTheReliefOfAFinerGround) {
  const LocalFrame frame({10.0, 20.0, 0.0});
  const Ridges ridges(frame);
  const RoughnessField field({0.001, 6.0}, 2);
  const GroundMesh mesh =
      build_ground_mesh(ridges, frame, 15.0, ridges.detail_m(), &field, 12.0).triangulated();
  ASSERT_FALSE(mesh.triangles.empty());
  double worst_m = 0.0;
  for (std::size_t t = 0; t < mesh.triangles.size(); t += 3) {
    Vec3 centroid{0.0, 0.0, 0.0};
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = mesh.triangles[t + k];
      centroid = centroid + (1.0 / 3.0) * Vec3{mesh.vertices_m[3 * v], mesh.vertices_m[3 * v + 1],
                                               mesh.vertices_m[3 * v + 2]};
    }
    const Geodetic below = frame.to_geodetic({centroid[0], centroid[1], 0.0});
    const Vec3 ground = frame.to_local(
        {below.lat_deg, below.lon_deg, ridges.height_m(below.lat_deg, below.lon_deg)});
    worst_m = std::max(worst_m, std::abs(centroid[2] - ground[2]));
  }
  EXPECT_LT(worst_m, 0.3);
}

// A region that needs more than 1024 nodes a side at L/3 is meshed at L/2 (then L), the relief
// under it of the setting's RMS; one that needs more even at L is refused, naming the setting and
// the limit, never smoothed.
TEST(Roughness, AWideBeamGetsACoarserLatticeOrARefusal) {
  const PlaneTerrain plane({45.0, 7.0, 600.0, 0.0, 0.0});
  const LocalFrame frame({45.0, 7.0, 600.0});
  const RoughnessField field({0.45, 0.5}, 11);
  const GroundMesh mesh =
      build_ground_mesh(plane, frame, 130.0, 1.0e9, &field, 120.0).triangulated();
  // 240 m / 0.1667 m = 1440 nodes a side at L/3; 960 at L/2 (1.85 million triangles).
  const std::size_t triangles = mesh.triangles.size() / 3;
  EXPECT_GT(triangles, 2u * 950 * 950);
  EXPECT_LT(triangles, 2u * 1000 * 1000);
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> u(-110.0, 110.0);
  // The mesh carries the L/2 lattice's relief.
  for (int k = 0; k < 20; ++k) {
    const double x = u(rng), y = u(rng);
    const Cover c = cover(mesh, x, y, -1e-7);
    ASSERT_GE(c.count, 1);
    const Geodetic on_mesh = frame.to_geodetic({x, y, c.z});
    const double relief_m = on_mesh.h_m - plane.height_m(on_mesh.lat_deg, on_mesh.lon_deg);
    EXPECT_NEAR(relief_m, field.height_m(on_mesh.lat_deg, on_mesh.lon_deg, 1), 2e-3);
  }
  double sum_sq = 0.0;
  constexpr int samples = 1500;
  for (int k = 0; k < samples; ++k) {
    const double x = u(rng), y = u(rng);
    const Geodetic g = frame.to_geodetic({x, y, 0.0});
    const double relief_m = field.height_m(g.lat_deg, g.lon_deg, 1);
    sum_sq += relief_m * relief_m;
  }
  // 1500 points over ~200 000 correlation cells: the RMS within 2 % (1 sigma), here 6 %.
  EXPECT_NEAR(std::sqrt(sum_sq / samples) / 0.45, 1.0, 0.06);
  const RoughnessField too_fine({0.45, 0.2}, 11);
  try {
    build_ground_mesh(plane, frame, 130.0, 1.0e9, &too_fine, 120.0);
    FAIL() << "a 0.2 m correlation under a 240 m field of view was meshed";
  } catch (const Error& error) {
    EXPECT_EQ(error.place(), "roughness/correlation_m");
    EXPECT_NE(error.message().find("limit is 1024"), std::string::npos) << error.message();
  }
}

TEST(Roughness, NoRoughnessLeavesTheMeshAlone) {
  const RoughnessField none({0.0, 2.0}, 1);
  const PlaneTerrain plane({0.0, 0.0, 0.0, 5.0, 0.0});
  const LocalFrame frame({0.0, 0.0, 0.0});
  const GroundMesh with = build_ground_mesh(plane, frame, 50.0, 25.0, &none, 20.0);
  const GroundMesh without = build_ground_mesh(plane, frame, 50.0, 25.0);
  EXPECT_EQ(with.vertices_m, without.vertices_m);
  EXPECT_EQ(with.triangles, without.triangles);
}

}  // namespace
}  // namespace glaswave
