// Ground meshes sampled from a terrain, and beam-weighted plane fits.
#include "terrain/ground_mesh.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include <Eigen/Dense>

namespace glaswave {

GroundMesh build_ground_mesh(const Terrain& terrain, const LocalFrame& frame, double half_size_m,
                             double spacing_m) {
  const int cells = std::clamp(static_cast<int>(std::ceil(2.0 * half_size_m / spacing_m)), 2, 4096);
  const int nodes = cells + 1;
  const double step_m = 2.0 * half_size_m / cells;

  GroundMesh mesh;
  mesh.vertices_m.reserve(3 * nodes * nodes);
  std::vector<bool> valid(nodes * nodes);
  mesh.min_height_m = std::numeric_limits<double>::infinity();
  mesh.max_height_m = -std::numeric_limits<double>::infinity();
  for (int j = 0; j < nodes; ++j) {
    for (int i = 0; i < nodes; ++i) {
      // A node is placed on the terrain below its east-north position, then expressed in the
      // frame: over a few hundred metres the frame's up and the local vertical agree.
      const Geodetic below = frame.to_geodetic({-half_size_m + i * step_m, -half_size_m + j * step_m, 0.0});
      const double height_m = terrain.height_m(below.lat_deg, below.lon_deg);
      valid[j * nodes + i] = std::isfinite(height_m);
      const Vec3 node = frame.to_local({below.lat_deg, below.lon_deg, valid[j * nodes + i] ? height_m : 0.0});
      for (double coordinate : node) mesh.vertices_m.push_back(static_cast<float>(coordinate));
      if (valid[j * nodes + i]) {
        mesh.min_height_m = std::min(mesh.min_height_m, node[2]);
        mesh.max_height_m = std::max(mesh.max_height_m, node[2]);
      }
    }
  }
  for (int j = 0; j < cells; ++j) {
    for (int i = 0; i < cells; ++i) {
      const std::uint32_t a = j * nodes + i, b = a + 1, c = a + nodes, d = c + 1;
      if (!(valid[a] && valid[b] && valid[c] && valid[d])) continue;
      mesh.triangles.insert(mesh.triangles.end(), {a, b, d, a, d, c});
    }
  }
  return mesh;
}

SurfaceOrientation fit_surface_orientation(const Terrain& terrain, const LocalFrame& frame,
                                           double sigma_m) {
  // Weighted least squares for z = c0 + c1 x + c2 y on a grid out to 2.5 sigma.
  constexpr int half_nodes = 10;
  const double step_m = 2.5 * sigma_m / half_nodes;
  Eigen::Matrix3d normal_matrix = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (int j = -half_nodes; j <= half_nodes; ++j) {
    for (int i = -half_nodes; i <= half_nodes; ++i) {
      const Geodetic below = frame.to_geodetic({i * step_m, j * step_m, 0.0});
      const double height_m = terrain.height_m(below.lat_deg, below.lon_deg);
      if (!std::isfinite(height_m)) continue;
      const Vec3 p = frame.to_local({below.lat_deg, below.lon_deg, height_m});
      const double weight = std::exp(-(p[0] * p[0] + p[1] * p[1]) / (2.0 * sigma_m * sigma_m));
      const Eigen::Vector3d row(1.0, p[0], p[1]);
      normal_matrix += weight * row * row.transpose();
      rhs += weight * p[2] * row;
    }
  }
  const Eigen::Vector3d c = normal_matrix.ldlt().solve(rhs);
  SurfaceOrientation orientation;
  const double rad = 180.0 / std::numbers::pi;
  orientation.slope_deg = std::atan(std::hypot(c[1], c[2])) * rad;
  // The surface faces down the gradient.
  orientation.aspect_deg = std::atan2(-c[1], -c[2]) * rad;
  if (orientation.aspect_deg < 0.0) orientation.aspect_deg += 360.0;
  if (orientation.slope_deg == 0.0) orientation.aspect_deg = 0.0;
  return orientation;
}

}  // namespace glaswave
