// The ground under a shot as a triangle mesh in the shot's local frame, and the terrain
// descriptors of a footprint (slope and aspect).
#pragma once

#include <cstdint>
#include <vector>

#include "terrain/local_frame.hpp"
#include "terrain/terrain.hpp"

namespace glaswave {

struct GroundMesh {
  std::vector<float> vertices_m;        // x, y, z triples in the local frame
  std::vector<std::uint32_t> triangles;  // vertex index triples; none over missing data
  double min_height_m = 0.0;             // of the vertices, in the local frame
  double max_height_m = 0.0;
};

// Samples the terrain on a square grid of half-width `half_size_m` about the frame's origin,
// at most `spacing_m` apart, and triangulates it. Cells touching missing data are left out.
GroundMesh build_ground_mesh(const Terrain& terrain, const LocalFrame& frame, double half_size_m,
                             double spacing_m);

struct SurfaceOrientation {
  double slope_deg = 0.0;
  double aspect_deg = 0.0;  // azimuth the surface faces, clockwise from north, [0, 360)
};

// Slope and aspect of the plane fitted to the terrain about the frame's origin, each point
// weighted by a Gaussian of RMS radius `sigma_m` (the beam's irradiance).
SurfaceOrientation fit_surface_orientation(const Terrain& terrain, const LocalFrame& frame,
                                           double sigma_m);

}  // namespace glaswave
