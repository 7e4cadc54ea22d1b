// The truth of a shot's vegetation, measured on its scene: what the beam falls on. (What grows
// in the scene comes from a vegetation source, pipeline/shot/vegetation_source.hpp.)
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

#include "pipeline/scene/scene.hpp"

namespace glaswave {

// Where the beam falls on a scene: its centre in the scene's frame (the footprint centre, the
// frame's origin when the scene is the shot's own) and its RMS radius, in the horizontal.
struct BeamSpot {
  double x_m = 0.0, y_m = 0.0;
  double sigma_m = 0.0;
};

// What the beam falls on, as the simulation knows it: the footprint's truth, each point of the
// ground weighted by the beam's irradiance (a Gaussian of RMS radius sigma_m about the spot's
// centre, in the horizontal).
struct VegetationTruth {
  double cover = 0.0;            // part of the beam's light falling on a crown's shadow from above
  double pai = 0.0;              // plant area crossed by a vertical line, beam-weighted mean
  double canopy_height_m = 0.0;  // highest foliage above the ground within 2 sigma of the centre
  // Part of the beam's light that a vertical line passes through the vegetation to the ground
  // (exp of its optical depth, G toward the zenith times the plant area crossed): the gap
  // probability GEDI L2B's cover is one minus.
  double gap_probability = 1.0;
};

// Along vertical lines; `nadir_projection[m]` is the foliage of material m's G toward the
// zenith (its leaves' projected area), for the gap probability.
VegetationTruth measure_vegetation(const Scene& scene, const BeamSpot& spot,
                                   const std::vector<double>& nadir_projection);

// measure_vegetation's vertical lines on one grid of the scene's frame (nodes at multiples of
// step_m east and north), each measured once, by the first footprint that weighs it, and shared
// by the footprints after: the truth of the shots sharing a stretch's scene, whose 41 x 41
// lines overlap almost entirely. A footprint weighs the nodes within 3 sigma of its centre (east
// and north), as measure_vegetation weighs its own grid; at step_m = 3 sigma / 20 the two are
// quadratures of the same integral on grids shifted by under a step. Thread-safe.
class TruthGrid {
 public:
  // The scene outlives the grid; nadir_projection as measure_vegetation's.
  TruthGrid(const Scene& scene, double step_m, std::vector<double> nadir_projection);
  ~TruthGrid();
  VegetationTruth measure(const BeamSpot& spot) const;

 private:
  struct Tile;
  // Tiles [ti0, ti1] x [tj0, tj1], row after row, each measured.
  void tiles(std::int64_t ti0, std::int64_t ti1, std::int64_t tj0, std::int64_t tj1,
             std::vector<Tile*>& found) const;

  const Scene& scene_;
  double step_m_;
  std::vector<double> nadir_projection_;
  mutable std::mutex mutex_;
  mutable std::map<std::pair<std::int64_t, std::int64_t>, std::unique_ptr<Tile>> tiles_;
};

// The same for facet trees: cover and height along the vertical lines (a line covered where the
// first surface it meets is a facet; an opaque facet leaves no gap: the gap probability is one
// less the cover), and the plant area as the facets' one-sided area under
// the beam's weight, over the weight's integral 2 pi sigma^2 (each model's area gathered on its
// area cells).
VegetationTruth measure_facets(const Scene& scene, const BeamSpot& spot);

}  // namespace glaswave
