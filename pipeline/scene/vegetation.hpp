// The vegetation of one shot in its local frame: the stand's trees near the footprint as
// crowns on their trunks, each standing on the terrain under its stem, or a homogeneous layer
// following the footprint's mean ground.
#pragma once

#include "canopy/forest.hpp"
#include "pipeline/scene/scene.hpp"
#include "terrain/ground_mesh.hpp"

namespace glaswave {

// What the beam falls on, as the simulation knows it: the footprint's truth, each point of the
// ground weighted by the beam's irradiance (a Gaussian of RMS radius sigma_m about the frame's
// origin, in the horizontal).
struct VegetationTruth {
  double cover = 0.0;            // part of the beam's light falling on a crown's shadow from above
  double pai = 0.0;              // plant area crossed by a vertical line, beam-weighted mean
  double canopy_height_m = 0.0;  // highest foliage above the ground within 2 sigma of the centre
};

VegetationTruth measure_vegetation(const Scene& scene, double sigma_m);

// Crowns are tagged with their forest kind as material.
Vegetation build_vegetation(const Forest& forest, const Terrain& terrain, const LocalFrame& frame,
                            double half_size_m, const SurfaceOrientation& ground);

}  // namespace glaswave
