// The truth's vertical lines on one grid shared by many footprints (TruthGrid): on a node it
// weighs the very lines a footprint's own grid would (measure_vegetation), anywhere else it is a
// quadrature of the same integral, checked against the closed form of one spheroid crown.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "pipeline/scene/vegetation.hpp"

namespace glaswave {
namespace {

// Level ground 240 m across at z = 0.
GroundMesh level_ground() {
  GroundMesh ground;
  ground.vertices_m = {-120.0f, -120.0f, 0.0f, 120.0f, -120.0f, 0.0f,
                       -120.0f, 120.0f,  0.0f, 120.0f, 120.0f,  0.0f};
  ground.triangles = {0, 1, 3, 0, 3, 2};
  return ground;
}

Crown spheroid(double x_m, double y_m, double radius_m, double half_height_m) {
  Crown crown;
  crown.base_m = {x_m, y_m, 6.0};
  crown.radius_m = radius_m;
  crown.half_height_m = half_height_m;
  crown.area_density_m2_m3 = 0.5;
  return crown;
}

constexpr double kSigma = 2.75;  // ATLAS's footprint: 11 m across at 1/e^2 is 4 sigma

TEST(TruthGrid, OnANodeWeighsTheLinesOfTheFootprintsOwnGrid) {
  const RayDevice device;
  Vegetation vegetation;
  vegetation.trunks.max_height_m = -std::numeric_limits<double>::infinity();
  // Crowns on both sides of the frame's origin, so that tiles of negative index are met.
  for (int k = -6; k <= 6; ++k)
    for (int m = -3; m <= 3; ++m)
      vegetation.crowns.push_back(
          spheroid(7.3 * k + 1.1 * m, 6.1 * m - 0.7 * k, 2.0 + 0.1 * (k + 6), 3.0 + 0.2 * (m + 3)));
  const Scene scene(device, level_ground(), vegetation);
  const double step_m = 0.15 * kSigma;
  const std::vector<double> nadir_projection = {0.5};  // material 0's G: spherical leaves
  const TruthGrid grid(scene, step_m, nadir_projection);
  for (const auto& [i, j] : std::vector<std::pair<int, int>>{
           {0, 0}, {-37, 5}, {17, -16}, {-100, -40}, {95, 31}, {-1, -1}, {16, 16}}) {
    const BeamSpot spot{i * step_m, j * step_m, kSigma};
    const VegetationTruth own = measure_vegetation(scene, spot, nadir_projection);
    const VegetationTruth shared = grid.measure(spot);
    EXPECT_GT(own.cover, 0.0) << i << ", " << j;
    EXPECT_NEAR(shared.cover, own.cover, 1e-9) << i << ", " << j;
    EXPECT_NEAR(shared.pai, own.pai, 1e-9) << i << ", " << j;
    EXPECT_NEAR(shared.canopy_height_m, own.canopy_height_m, 1e-6) << i << ", " << j;
    EXPECT_NEAR(shared.gap_probability, own.gap_probability, 1e-9) << i << ", " << j;
    EXPECT_LT(own.gap_probability, 1.0 - 0.05 * own.cover) << i << ", " << j;
  }
}

// One spheroid crown (radius R, half-height h, density u) centred under a footprint between the
// nodes: a vertical line at r crosses 2 h sqrt(1 - r^2 / R^2) of it. Over the grid's square of
// +-3 sigma, the Gaussian-weighted cover is P(r < R) / P(square) with P(r < R) = 1 -
// exp(-R^2 / 2 sigma^2) and P(square) = erf(3 / sqrt 2)^2; the PAI the same weights' mean of
// u 2 h sqrt(1 - r^2 / R^2), integrated here in r, and the gap probability one less the same
// weights' mean of 1 - exp(-G u 2 h sqrt(1 - r^2 / R^2)) (G = 0.7, the material's G toward the
// zenith, not spherical leaves' 1/2: the truth takes the one it is given); the height is the
// crown's top.
TEST(TruthGrid, BetweenTheNodesIsTheSameIntegral) {
  const RayDevice device;
  const double radius_m = 4.0, half_height_m = 5.0, x_m = 5.31, y_m = -7.07;
  Vegetation vegetation;
  vegetation.trunks.max_height_m = -std::numeric_limits<double>::infinity();
  vegetation.crowns.push_back(spheroid(x_m, y_m, radius_m, half_height_m));
  const Scene scene(device, level_ground(), vegetation);
  const double g = 0.7;
  const TruthGrid grid(scene, 0.15 * kSigma, {g});
  const VegetationTruth truth = grid.measure({x_m, y_m, kSigma});
  const double square = std::pow(std::erf(3.0 / std::sqrt(2.0)), 2);
  const double two_var = 2.0 * kSigma * kSigma;
  double pai = 0.0, intercepted = 0.0;
  constexpr int steps = 100000;
  for (int k = 0; k < steps; ++k) {
    const double r = (k + 0.5) * radius_m / steps;
    const double area = 0.5 * 2.0 * half_height_m * std::sqrt(1.0 - r * r / (radius_m * radius_m));
    const double weight = std::exp(-r * r / two_var) * 2.0 * r / two_var * (radius_m / steps);
    pai += area * weight;
    intercepted += (1.0 - std::exp(-g * area)) * weight;
  }
  // A node every 0.41 m, some 300 over the disc: the nodes just inside and just outside its edge
  // nearly cancel, to a few tenths of a percent of the cover and the PAI.
  EXPECT_NEAR(truth.cover, (1.0 - std::exp(-radius_m * radius_m / two_var)) / square, 0.005);
  EXPECT_NEAR(truth.pai, pai / square, 0.005);
  EXPECT_NEAR(truth.gap_probability, 1.0 - intercepted / square, 0.005);
  // The nearest node to the apex is within 0.3 m: the top there is h r^2 / (2 R^2) = 0.014 m low.
  EXPECT_NEAR(truth.canopy_height_m, 6.0 + 2.0 * half_height_m, 0.02);
}

}  // namespace
}  // namespace glaswave
