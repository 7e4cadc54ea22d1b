// The ray against the terrain. A height field is only known through point queries, so the
// march takes steps no longer than the clearance above the ground divided by the fastest rate
// at which that clearance can shrink (the ray's descent plus ground rising at the steepest
// slope): such a step cannot pass through any ground, so the first crossing is never skipped,
// however steep or folded the terrain. Near the ground the steps are floored at a few tolerances
// and the crossing they bracket is refined by the Illinois variant of regula falsi.
#include "footprints/terrain_intersection.hpp"

#include <GeographicLib/Constants.hpp>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

namespace glaswave {
namespace {

constexpr double deg = std::numbers::pi / 180.0;

// Both parameters where origin + t * direction meets the ellipsoid raised by height_m, t0 <= t1.
std::optional<std::pair<double, double>> ellipsoid_roots(const Vec3& origin, const Vec3& direction,
                                                         double height_m) {
  const double a = GeographicLib::Constants::WGS84_a() + height_m;
  const double b =
      GeographicLib::Constants::WGS84_a() * (1.0 - GeographicLib::Constants::WGS84_f()) + height_m;
  const Vec3 o{origin[0] / a, origin[1] / a, origin[2] / b};
  const Vec3 d{direction[0] / a, direction[1] / a, direction[2] / b};
  const double qa = dot(d, d), qb = 2.0 * dot(o, d), qc = dot(o, o) - 1.0;
  const double discriminant = qb * qb - 4.0 * qa * qc;
  if (discriminant < 0.0 || qa == 0.0) return std::nullopt;
  // Written to avoid cancellation between -qb and the square root.
  const double q = -0.5 * (qb + std::copysign(std::sqrt(discriminant), qb));
  double t0 = q / qa, t1 = q != 0.0 ? qc / q : -t0;
  if (t0 > t1) std::swap(t0, t1);
  return std::make_pair(t0, t1);
}

// Sine of the angle between a direction and the geodetic vertical at a point.
double sine_from_vertical(const Vec3& point_ecef, const Vec3& unit_direction) {
  const Geodetic at = geodetic_from_ecef(point_ecef);
  return std::min(1.0, norm(cross(unit_direction, enu_axes(at.lat_deg, at.lon_deg)[2])));
}

struct Sample {
  double t = 0.0;
  double height_m = 0.0;     // of the ray point above WGS84
  double clearance_m = 0.0;  // above the ground under it; NaN where the terrain has no data
};

// The ray's points, queried against the terrain and counted.
struct Probe {
  const Terrain& terrain;
  const Vec3& origin;
  const Vec3& direction;
  int queries = 0;

  Sample operator()(double t) {
    ++queries;
    const Geodetic p = geodetic_from_ecef(origin + t * direction);
    return Sample{t, p.h_m, p.h_m - terrain.height_m(p.lat_deg, p.lon_deg)};
  }
};

// How far the search goes along the ray, and the largest sine of the ray's angle from the
// vertical over it. The search ends where the ray goes below the lowest ground, or, when it passes
// beside the Earth, where it has climbed back to the height it started from; none when the ray
// points away from the Earth.
struct SearchRange {
  double t_end = 0.0;
  double sine_bound = 1.0;
};

std::optional<SearchRange> search_range(const Vec3& origin, const Vec3& direction,
                                        const TerrainLimits& limits) {
  SearchRange range;
  const auto bottom = ellipsoid_roots(origin, direction, limits.min_height_m);
  if (bottom && bottom->first >= 0.0) {
    range.t_end = bottom->first;
    // The angle from the local vertical only grows as a descending straight ray goes down, so
    // its value at the end bounds the whole search; a margin covers the ellipsoid's departure
    // from a sphere.
    range.sine_bound =
        std::min(1.0, sine_from_vertical(origin + range.t_end * direction, direction) + 0.01);
    return range;
  }
  const auto level = ellipsoid_roots(origin, direction, geodetic_from_ecef(origin).h_m);
  if (!level || level->second <= 0.0) return std::nullopt;
  range.t_end = level->second;
  return range;
}

// The crossing bracketed by `above` (above the ground) and `below` (on or under it), refined by
// the Illinois variant of regula falsi to `tolerance_m` along the ray.
double refine_crossing(Probe& probe, const Sample& above, const Sample& below, double tolerance_m) {
  double a = above.t, fa = above.clearance_m, b = below.t, fb = below.clearance_m;
  int side = 0;
  for (int iteration = 0; iteration < 200 && b - a > tolerance_m && fb != 0.0; ++iteration) {
    double t = b - fb * (b - a) / (fb - fa);
    if (!(t > a && t < b)) t = 0.5 * (a + b);
    const double ft = probe(t).clearance_m;
    if (std::isnan(ft)) {  // a hole in the data inside the bracket counts as open air
      a = t;
      continue;
    }
    if (ft > 0.0) {
      a = t;
      fa = ft;
      if (side == 1) fb *= 0.5;  // Illinois: keep the stale end from stalling the bracket
      side = 1;
    } else {
      b = t;
      fb = ft;
      if (side == -1) fa *= 0.5;
      side = -1;
    }
  }
  return fb == 0.0 ? b : 0.5 * (a + b);
}

// The march: the first crossing of the ground along [0, range.t_end], as a parameter along the
// ray; none where the ray meets no ground, starts under it, or comes out of a hole in the data
// already under it.
std::optional<double> march(Probe& probe, const SearchRange& range, const TerrainLimits& limits) {
  // The clearance shrinks at most by the ray's descent (<= 1 per metre along it) plus the rise of
  // the steepest ground across the horizontal distance the ray covers (<= sine_bound per metre,
  // with 5 % for the foot point moving faster than the ray below the ellipsoid and for terrain
  // slopes measured in a local plane).
  const double max_gradient = std::tan(std::clamp(limits.max_slope_deg, 0.0, 89.9) * deg);
  const double shrink_rate = 1.0 + 1.05 * max_gradient * range.sine_bound;
  const double min_step_m = 20.0 * limits.tolerance_m;
  // Over terrain without data the ray moves on by half the terrain's detail horizontally.
  const double terrain_detail_m = probe.terrain.detail_m();
  const double detail_m =
      std::isfinite(terrain_detail_m) && terrain_detail_m > 0.0 ? terrain_detail_m : 1.0;
  const double no_data_step_m =
      std::max(min_step_m, 0.5 * detail_m / std::max(range.sine_bound, 1e-9));

  Sample current = probe(0.0);
  if (current.clearance_m <= 0.0) return std::nullopt;  // the origin is under the ground
  bool above_ground = current.clearance_m > 0.0;        // false while over terrain without data
  Sample above = current;                               // last sample known above the ground
  while (current.t < range.t_end) {
    double step_m = no_data_step_m;
    if (above_ground) {
      step_m = std::max(current.clearance_m / shrink_rate, min_step_m);
    } else if (current.height_m > limits.max_height_m) {
      // No data, and no ground this high: go straight down to where ground may be.
      const auto top = ellipsoid_crossing(probe.origin, probe.direction, limits.max_height_m);
      step_m = top && *top > current.t ? std::max(*top - current.t, min_step_m) : no_data_step_m;
    }
    const Sample next = probe(std::min(current.t + step_m, range.t_end));
    if (std::isnan(next.clearance_m)) {
      above_ground = false;
    } else if (next.clearance_m > 0.0) {
      above_ground = true;
      above = next;
    } else if (!above_ground) {
      // The ray came out of a hole in the data already under the ground: where it met the ground
      // is unknown, so the shot has no footprint.
      return std::nullopt;
    } else {
      return refine_crossing(probe, above, next, limits.tolerance_m);
    }
    current = next;
  }
  return std::nullopt;
}

}  // namespace

std::optional<double> ellipsoid_crossing(const Vec3& origin_ecef, const Vec3& direction_ecef,
                                         double height_m) {
  const auto roots = ellipsoid_roots(origin_ecef, direction_ecef, height_m);
  if (!roots || roots->second < 0.0) return std::nullopt;
  return roots->first >= 0.0 ? roots->first : roots->second;
}

std::optional<Vec3> intersect_terrain(const Terrain& terrain, const Vec3& origin_ecef,
                                      const Vec3& direction_ecef, const TerrainLimits& limits,
                                      IntersectionStats* stats) {
  const Vec3 direction = normalized(direction_ecef);
  if (!std::isfinite(direction[0]) || !std::isfinite(direction[1]) || !std::isfinite(direction[2]))
    return std::nullopt;
  const auto range = search_range(origin_ecef, direction, limits);
  if (!range) return std::nullopt;
  Probe probe{terrain, origin_ecef, direction};
  const std::optional<double> t = march(probe, *range, limits);
  if (stats) stats->height_queries += probe.queries;
  if (!t) return std::nullopt;
  return origin_ecef + *t * direction;
}

}  // namespace glaswave
