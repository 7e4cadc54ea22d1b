// The truth of a shot's vegetation, measured on its scene: what the beam falls on. (What grows
// in the scene comes from a vegetation source, pipeline/shot/vegetation_source.hpp.)
#pragma once

#include "pipeline/scene/scene.hpp"

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

// The same for facet trees: cover and height along the vertical lines (a line covered where the
// first surface it meets is a facet), and the plant area as the facets' one-sided area under
// the beam's weight, over the weight's integral 2 pi sigma^2 (each model's area gathered on its
// area cells).
VegetationTruth measure_facets(const Scene& scene, double sigma_m);

}  // namespace glaswave
