// Ground meshes from terrains (with roughness), and beam-weighted plane fits over them.
#include "terrain/ground_mesh.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

#include "terrain/roughness.hpp"

namespace glaswave {

void triangulate_grid(int ni, int nj, const std::vector<std::uint32_t>& node_vertex,
                      std::vector<std::uint32_t>& triangles) {
  for (int j = 0; j + 1 < nj; ++j) {
    for (int i = 0; i + 1 < ni; ++i) {
      const std::size_t n = static_cast<std::size_t>(j) * ni + i;
      triangulate_cell(node_vertex[n], node_vertex[n + 1], node_vertex[n + ni],
                       node_vertex[n + ni + 1], triangles);
    }
  }
}

GroundMesh GroundMesh::triangulated() const {
  GroundMesh mesh = *this;
  mesh.grids.clear();
  for (const MeshGrid& grid : grids)
    triangulate_grid(grid.width, grid.height, grid.nodes, mesh.triangles);
  return mesh;
}

void mesh_grid_cells(int ni, int nj, const std::vector<std::uint32_t>& node_vertex,
                     const std::vector<char>& cell_in, GroundMesh& mesh) {
  auto node = [&](int i, int j) { return node_vertex[static_cast<std::size_t>(j) * ni + i]; };
  auto wanted = [&](int i, int j) {
    return cell_in.empty() || cell_in[static_cast<std::size_t>(j) * (ni - 1) + i] != 0;
  };
  // Each cell's kind, found once: 0 not wanted, 1 wanted with a node missing, 2 whole.
  std::vector<char> kind(static_cast<std::size_t>(std::max(ni - 1, 0)) * std::max(nj - 1, 0), 0);
  for (int j = 0; j + 1 < nj; ++j)
    for (int i = 0; i + 1 < ni; ++i)
      if (wanted(i, j))
        kind[static_cast<std::size_t>(j) * (ni - 1) + i] =
            node(i, j) != no_vertex && node(i + 1, j) != no_vertex && node(i, j + 1) != no_vertex &&
                    node(i + 1, j + 1) != no_vertex
                ? 2
                : 1;
  auto whole = [&](int i, int j) { return kind[static_cast<std::size_t>(j) * (ni - 1) + i] == 2; };
  // Rectangles of whole cells [i0, i1) x [j0, j): each row's runs, a run going on from the row
  // below when it spans the same cells.
  struct Open {
    int i0, i1, j0;
  };
  std::vector<Open> open, still;
  auto close = [&](const Open& r, int j1) {
    MeshGrid grid;
    grid.width = r.i1 - r.i0 + 1;
    grid.height = j1 - r.j0 + 1;
    grid.nodes.reserve(static_cast<std::size_t>(grid.width) * grid.height);
    for (int j = r.j0; j <= j1; ++j)
      for (int i = r.i0; i <= r.i1; ++i) grid.nodes.push_back(node(i, j));
    mesh.grids.push_back(std::move(grid));
  };
  for (int j = 0; j < nj; ++j) {
    std::vector<std::array<int, 2>> runs;
    for (int i = 0; j + 1 < nj && i + 1 < ni;) {
      if (!whole(i, j)) {
        ++i;
        continue;
      }
      const int i0 = i;
      while (i + 1 < ni && whole(i, j) && i - i0 + 1 < max_grid_nodes) ++i;
      runs.push_back({i0, i});
    }
    still.clear();
    for (const Open& r : open) {
      const auto run = std::find(runs.begin(), runs.end(), std::array<int, 2>{r.i0, r.i1});
      if (run == runs.end() || j - r.j0 + 1 == max_grid_nodes) {
        close(r, j);
        continue;
      }
      still.push_back(r);
      runs.erase(run);
    }
    for (const auto& run : runs) still.push_back({run[0], run[1], j});
    open.swap(still);
  }
  // The cells wanted but not whole: the triangles that stand on three nodes.
  for (int j = 0; j + 1 < nj; ++j)
    for (int i = 0; i + 1 < ni; ++i)
      if (kind[static_cast<std::size_t>(j) * (ni - 1) + i] == 1)
        triangulate_cell(node(i, j), node(i + 1, j), node(i, j + 1), node(i + 1, j + 1),
                         mesh.triangles);
}

GroundMesh build_ground_mesh(const Terrain& terrain, const LocalFrame& frame, double half_size_m,
                             double spacing_m, const RoughnessField* roughness,
                             double rough_half_size_m) {
  GroundMesh base = terrain.mesh(frame, half_size_m, spacing_m);
  if (!roughness || !roughness->enabled()) return base;
  const double rough_m =
      rough_half_size_m > 0.0 ? std::min(rough_half_size_m, half_size_m) : half_size_m;
  return roughness->roughen(base, frame, rough_m, std::min(spacing_m, terrain.detail_m()));
}

GroundMesh sample_ground_mesh(const Terrain& terrain, const LocalFrame& frame, double half_size_m,
                              double spacing_m) {
  const int cells = std::clamp(static_cast<int>(std::ceil(2.0 * half_size_m / spacing_m)), 2, 4096);
  const int nodes = cells + 1;
  const double step_m = 2.0 * half_size_m / cells;

  GroundMesh mesh;
  mesh.vertices_m.reserve(3 * nodes * nodes);
  std::vector<std::uint32_t> node_vertex(nodes * nodes, no_vertex);
  mesh.min_height_m = std::numeric_limits<double>::infinity();
  mesh.max_height_m = -std::numeric_limits<double>::infinity();
  for (int j = 0; j < nodes; ++j) {
    for (int i = 0; i < nodes; ++i) {
      // A node is placed on the terrain below its east-north position, then expressed in the
      // frame: over a few hundred metres the frame's up and the local vertical agree.
      const Geodetic below =
          frame.to_geodetic({-half_size_m + i * step_m, -half_size_m + j * step_m, 0.0});
      const double height_m = terrain.height_m(below.lat_deg, below.lon_deg);
      const bool valid = std::isfinite(height_m);
      const Vec3 node = frame.to_local({below.lat_deg, below.lon_deg, valid ? height_m : 0.0});
      for (double coordinate : node) mesh.vertices_m.push_back(static_cast<float>(coordinate));
      if (valid) {
        node_vertex[j * nodes + i] = j * nodes + i;
        mesh.min_height_m = std::min(mesh.min_height_m, node[2]);
        mesh.max_height_m = std::max(mesh.max_height_m, node[2]);
      }
    }
  }
  triangulate_grid(nodes, nodes, node_vertex, mesh.triangles);
  if (mesh.triangles.empty()) mesh.min_height_m = mesh.max_height_m = 0.0;
  return mesh;
}

namespace {

// exp(-600) = 2.6e-261: the weights of a triangle whose exponents all lie above it, and the
// ratios between them (at most e^600), stay within a double's range.
constexpr double kLowestExponent = -600.0;

// The normal equations of a weighted least-squares fit of z = c0 + c1 x + c2 y over a surface,
// each part of it weighted by its horizontal area and a beam's Gaussian irradiance there.
struct BeamWeightedPlaneFit {
  Eigen::Vector3d axis;  // the beam's, unit, through the origin
  double sigma_m;

  // A triangle, cut into m^2 equal parts no wider than sigma / 4, each weighted at its centroid.
  void add_triangle(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                    const Eigen::Vector3d& p2) {
    const Eigen::Vector3d e1 = p1 - p0, e2 = p2 - p0;
    const double area_m2 = 0.5 * std::abs(e1.x() * e2.y() - e1.y() * e2.x());
    if (area_m2 == 0.0) return;
    // Far triangles weigh nothing: skip them before cutting them up.
    const Eigen::Vector3d centroid = (p0 + p1 + p2) / 3.0;
    const double radius_m =
        std::max({(p0 - centroid).norm(), (p1 - centroid).norm(), (p2 - centroid).norm()});
    const double centroid_off_m =
        std::sqrt(std::max(0.0, centroid.squaredNorm() - std::pow(centroid.dot(axis), 2)));
    if (centroid_off_m - radius_m > 6.0 * sigma_m) return;
    const double longest_m =
        std::max({e1.head<2>().norm(), e2.head<2>().norm(), (p2 - p1).head<2>().norm()});
    const int m = std::clamp(static_cast<int>(std::ceil(longest_m / (sigma_m / 4.0))), 1, 64);
    const double part_area_m2 = area_m2 / (m * m);
    // The parts' centroids lie on two lattices, p0 + (i + c) d1 + (j + c) d2 with c = 1/3 (the
    // parts pointing like the triangle, i + j < m) and 2/3 (those between, upside down,
    // i + j + 2 <= m). The weight's exponent, -|q|^2_perp / 2 sigma^2, is quadratic in i and j:
    // along a row each weight is the last times a ratio that itself changes by a constant
    // factor, and so are the rows' first weights and ratios. A few exponentials a triangle
    // instead of one a part (they were a fifth of a short shot's time).
    const Eigen::Matrix3d perp = Eigen::Matrix3d::Identity() - axis * axis.transpose();
    const Eigen::Vector3d d1 = e1 / m, d2 = e2 / m;
    const double exponent_per_m2 = -0.5 / (sigma_m * sigma_m);
    const Eigen::Vector3d perp_d1 = perp * d1, perp_d2 = perp * d2;
    // The exponent is lowest at a corner. Where a corner's weight is below what a double holds
    // (a beam much narrower than the cells), the recurrence would carry zeros from there: each
    // part's weight is then computed alone.
    auto exponent = [&](const Eigen::Vector3d& p) { return exponent_per_m2 * p.dot(perp * p); };
    const bool alone = std::min({exponent(p0), exponent(p1), exponent(p2)}) < kLowestExponent;
    const double ratio_step_j = std::exp(2.0 * exponent_per_m2 * d2.dot(perp_d2));  // along a row
    const double ratio_step_i =
        std::exp(2.0 * exponent_per_m2 * d1.dot(perp_d2));  // of rows' j-ratios
    const double first_step_i =
        std::exp(2.0 * exponent_per_m2 * d1.dot(perp_d1));  // of rows' i-ratios
    auto lattice = [&](double c, int rows) {                // row i holds rows - i parts
      const Eigen::Vector3d q = p0 + c * d1 + c * d2;
      const Eigen::Vector3d perp_q = perp * q;
      double first = std::exp(exponent_per_m2 * q.dot(perp_q));  // the weight of (0, 0)
      // Ratios from (i, 0) to (i + 1, 0) and from (i, 0) to (i, 1), at i = 0.
      double ratio_i = std::exp(exponent_per_m2 * (2.0 * d1.dot(perp_q) + d1.dot(perp_d1)));
      double ratio_j = std::exp(exponent_per_m2 * (2.0 * d2.dot(perp_q) + d2.dot(perp_d2)));
      for (int i = 0; i < rows; ++i) {
        double weight = first, ratio = ratio_j;
        Eigen::Vector3d p = q + i * d1;
        for (int j = 0; j < rows - i; ++j) {
          add(p, part_area_m2 * (alone ? std::exp(exponent(p)) : weight));
          weight *= ratio;
          ratio *= ratio_step_j;
          p += d2;
        }
        first *= ratio_i;
        ratio_i *= first_step_i;
        ratio_j *= ratio_step_i;
      }
    };
    lattice(1.0 / 3.0, m);
    lattice(2.0 / 3.0, m - 1);
  }

  void add(const Eigen::Vector3d& p, double weight) {
    const double wx = weight * p.x(), wy = weight * p.y();
    sum_w += weight;
    sum_wx += wx;
    sum_wy += wy;
    sum_wxx += wx * p.x();
    sum_wxy += wx * p.y();
    sum_wyy += wy * p.y();
    sum_wz += weight * p.z();
    sum_wxz += wx * p.z();
    sum_wyz += wy * p.z();
  }

  // The sums as the normal equations of z = c0 + c1 x + c2 y.
  Eigen::Matrix3d normal_matrix() const {
    Eigen::Matrix3d matrix;
    matrix << sum_w, sum_wx, sum_wy, sum_wx, sum_wxx, sum_wxy, sum_wy, sum_wxy, sum_wyy;
    return matrix;
  }
  Eigen::Vector3d rhs() const { return {sum_wz, sum_wxz, sum_wyz}; }

  // The weighted sums of 1, x, y and their products, and of z times each.
  double sum_w = 0.0, sum_wx = 0.0, sum_wy = 0.0, sum_wxx = 0.0, sum_wxy = 0.0, sum_wyy = 0.0;
  double sum_wz = 0.0, sum_wxz = 0.0, sum_wyz = 0.0;
};

}  // namespace

SurfaceOrientation fit_surface_orientation(const Terrain& terrain, const LocalFrame& frame,
                                           double sigma_m, const Vec3& beam_axis) {
  const Vec3 axis = normalized(beam_axis);
  // The beam's trace on the ground lengthens as 1 / cos(off-nadir); 3.5 sigma leaves out 0.2 %
  // of its weight.
  const double reach_m = 3.5 * sigma_m / std::max(0.2, std::abs(axis[2]));
  // Nodes a sigma apart are enough for terrains sampled between their nodes (a plane): each
  // triangle is cut into parts of sigma / 4 below. A DEM meshes on its own nodes.
  const GroundMesh mesh = terrain.mesh(frame, reach_m, std::min(terrain.detail_m(), sigma_m));
  BeamWeightedPlaneFit fit{Eigen::Vector3d(axis[0], axis[1], axis[2]), sigma_m};
  auto vertex = [&](std::uint32_t index) {
    return Eigen::Vector3d(mesh.vertices_m[3 * index], mesh.vertices_m[3 * index + 1],
                           mesh.vertices_m[3 * index + 2]);
  };
  for (std::size_t t = 0; t < mesh.triangles.size(); t += 3)
    fit.add_triangle(vertex(mesh.triangles[t]), vertex(mesh.triangles[t + 1]),
                     vertex(mesh.triangles[t + 2]));

  SurfaceOrientation orientation;
  if (fit.sum_w <= 0.0) {  // no ground under the beam
    orientation.slope_deg = orientation.aspect_deg = std::numeric_limits<double>::quiet_NaN();
    return orientation;
  }
  const Eigen::Vector3d c = fit.normal_matrix().ldlt().solve(fit.rhs());
  const double rad = 180.0 / std::numbers::pi;
  orientation.slope_deg = std::atan(std::hypot(c[1], c[2])) * rad;
  // The surface faces down the gradient.
  orientation.aspect_deg = std::atan2(-c[1], -c[2]) * rad;
  if (orientation.aspect_deg < 0.0) orientation.aspect_deg += 360.0;
  if (orientation.aspect_deg >= 360.0)
    orientation.aspect_deg -= 360.0;  // -1e-17 + 360 rounds to 360
  if (orientation.slope_deg == 0.0) orientation.aspect_deg = 0.0;
  return orientation;
}

}  // namespace glaswave
