// Where a ray (a laser beam, or one ray of it) first meets the terrain: the WGS84 ellipsoid in
// closed form for the search interval, then a march in steps that cannot jump over the ground,
// refined by bracketing to the millimetre.
#pragma once

#include <optional>

#include "terrain/local_frame.hpp"
#include "terrain/terrain.hpp"

namespace glaswave {

// What the march may assume about the ground, since a Terrain only answers height queries.
struct TerrainLimits {
  // No ground lies below this height (m above WGS84): the march stops there. The deepest land
  // surface on Earth is about -430 m; -12 km leaves room for synthetic planes and trenches.
  double min_height_m = -12000.0;
  // Where the terrain has no data, no ground lies above this height (Everest is about 8820 m
  // above WGS84), so a ray over a hole in a DEM skips straight down to it.
  double max_height_m = 9000.0;
  // The steepest ground: steps are chosen so that ground rising this fast cannot be jumped over.
  // Steeper ground (cliffs in metre-scale DEMs) may be entered a few centimetres late.
  double max_slope_deg = 85.0;
  // The ray position is refined until it is known to this length along the ray (m).
  double tolerance_m = 1.0e-3;
};

// Ray-march statistics, for tests and benchmarks.
struct IntersectionStats {
  int height_queries = 0;
};

// The first point where the ray origin + t * direction (t >= 0) meets the terrain, or empty when
// it never does (it points away, passes over terrain without data, or misses the Earth). The
// origin must be above the ground (a spacecraft); an origin below it gives an empty answer.
// Heights of NaN are read as "no ground here".
std::optional<Vec3> intersect_terrain(const Terrain& terrain, const Vec3& origin_ecef,
                                      const Vec3& direction_ecef, const TerrainLimits& limits = {},
                                      IntersectionStats* stats = nullptr);

// Smallest t >= 0 where origin + t * direction meets the WGS84 ellipsoid raised by height_m
// (approximated as an ellipsoid with both semi-axes raised, exact at the surface), or empty.
// `direction` need not be a unit vector; t is in units of its length.
std::optional<double> ellipsoid_crossing(const Vec3& origin_ecef, const Vec3& direction_ecef,
                                         double height_m);

}  // namespace glaswave
