// The ground under a shot as a triangle mesh in the shot's local frame, and the terrain
// descriptors of a footprint (slope and aspect).
#pragma once

#include <cstdint>
#include <vector>

#include "terrain/local_frame.hpp"
#include "terrain/terrain.hpp"

namespace glaswave {

class RoughnessField;  // terrain/roughness.hpp

struct GroundMesh {
  std::vector<float> vertices_m;         // x, y, z triples in the local frame
  std::vector<std::uint32_t> triangles;  // vertex index triples; none over missing data
  double min_height_m = 0.0;             // of the vertices triangles use, in the local frame
  double max_height_m = 0.0;
};

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
