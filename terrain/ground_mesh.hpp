// The ground under a shot as a triangle mesh in the shot's local frame, and the terrain
// descriptors of a footprint (slope and aspect).
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include "terrain/local_frame.hpp"
#include "terrain/terrain.hpp"

namespace glaswave {

class RoughnessField;  // terrain/roughness.hpp

// A rectangle of a grid of nodes whose every cell is meshed (the roughness's lattice under the
// beams, a trunk's faces): node (a, b), a < width, b < height, is vertex `nodes[b * width + a]`,
// and each cell is cut as triangulate_grid cuts it. The ray tracer builds such a patch as a
// grid, far cheaper to index than its triangles (pipeline/scene/).
struct MeshGrid {
  int width = 0, height = 0;  // nodes, each from 2 to max_grid_nodes
  std::vector<std::uint32_t> nodes;
};
// Embree's limit on a grid's side.
inline constexpr int max_grid_nodes = 32767;

struct GroundMesh {
  std::vector<float> vertices_m;         // x, y, z triples in the local frame
  std::vector<std::uint32_t> triangles;  // vertex index triples; none over missing data
  std::vector<MeshGrid> grids;           // more of the surface, beside the triangles
  double min_height_m = 0.0;             // of the vertices the surface uses, in the local frame
  double max_height_m = 0.0;

  // The same surface as triangles alone: `triangles`, then each grid's cells' two triangles.
  GroundMesh triangulated() const;
};

// The one triangulation of a grid of heights (sampled terrains, DEMs, the roughness lattice):
// each cell (i, j) is cut by the diagonal from node (i, j) to (i + 1, j + 1) into the triangles
// (a, b, d) and (a, d, c), a = (i, j), b = (i + 1, j), c = (i, j + 1), d = (i + 1, j + 1).

// A grid node without a vertex (no data there).
inline constexpr std::uint32_t no_vertex = std::numeric_limits<std::uint32_t>::max();

// Appends the triangles of one cell, a = (i, j), b = (i + 1, j), c = (i, j + 1), d = (i + 1, j +
// 1), as above: each that stands on three vertices.
inline void triangulate_cell(std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d,
                             std::vector<std::uint32_t>& triangles) {
  if (a != no_vertex && b != no_vertex && d != no_vertex)
    triangles.insert(triangles.end(), {a, b, d});
  if (a != no_vertex && d != no_vertex && c != no_vertex)
    triangles.insert(triangles.end(), {a, d, c});
}

// Appends the triangles of a grid of ni x nj nodes, node (i, j) being vertex
// `node_vertex[j * ni + i]`. Each triangle stands on its own three nodes: a node without a
// vertex removes only the triangles that touch it.
void triangulate_grid(int ni, int nj, const std::vector<std::uint32_t>& node_vertex,
                      std::vector<std::uint32_t>& triangles);

// The cells of a grid of ni x nj nodes (as above) for which `cell_in[j * (ni - 1) + i]` holds
// (every cell when `cell_in` is empty), added to `mesh`: those whose four nodes have vertices as
// MeshGrids (rectangles, merged row by row), the rest as triangulate_grid's triangles.
void mesh_grid_cells(int ni, int nj, const std::vector<std::uint32_t>& node_vertex,
                     const std::vector<char>& cell_in, GroundMesh& mesh);

// The height at (fu, fv) in [0, 1]^2 of a cell on the triangle of the triangulation holding it,
// `height(di, dj)` giving the height of node (i + di, j + dj); only the three nodes of that
// triangle are asked for.
template <typename NodeHeight>
double cell_height(double fu, double fv, NodeHeight height) {
  const double a = height(0, 0), d = height(1, 1);
  if (fu >= fv) {
    const double b = height(1, 0);
    return a + fu * (b - a) + fv * (d - b);
  }
  const double c = height(0, 1);
  return a + fv * (c - a) + fu * (d - c);
}

// The ground a shot's rays meet: the terrain's own mesh over (at least) the square of half-width
// `half_size_m` about the frame's origin (Terrain::mesh; `spacing_m` is the grid of terrains that
// only answer height queries), with the roughness's relief added within `rough_half_size_m` of
// the origin (the whole square when 0) when a roughness field with a non-zero RMS is given.
GroundMesh build_ground_mesh(const Terrain& terrain, const LocalFrame& frame, double half_size_m,
                             double spacing_m, const RoughnessField* roughness = nullptr,
                             double rough_half_size_m = 0.0);

// What Terrain::mesh does by default: samples the terrain on a square grid of half-width
// `half_size_m` about the frame's origin, at most `spacing_m` apart, and triangulates it with the
// diagonal from node (i, j) to (i + 1, j + 1). Triangles touching missing data are left out.
GroundMesh sample_ground_mesh(const Terrain& terrain, const LocalFrame& frame, double half_size_m,
                              double spacing_m);

struct SurfaceOrientation {
  double slope_deg = 0.0;
  double aspect_deg = 0.0;  // azimuth the surface faces, clockwise from north, [0, 360)
};

// Slope and aspect of the plane fitted by least squares to the terrain's mesh about the frame's
// origin (the footprint centre), each part of the surface weighted by the beam's irradiance: a
// Gaussian of RMS width `sigma_m` across the beam axis `beam_axis` (local frame, toward the
// ground; nadir by default). The mesh is integrated triangle by triangle, so a coarse DEM under a
// narrow beam is weighted as finely as a fine one.
SurfaceOrientation fit_surface_orientation(const Terrain& terrain, const LocalFrame& frame,
                                           double sigma_m,
                                           const Vec3& beam_axis = {0.0, 0.0, -1.0});

}  // namespace glaswave
