// Ray-crown intervals for ellipsoids and cones, in closed form.
#include "canopy/crown.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace glaswave {
namespace {

constexpr double infinity = std::numeric_limits<double>::infinity();

// Real roots of a t^2 + b t + c = 0 in increasing order, written to avoid cancellation.
std::optional<std::pair<double, double>> quadratic_roots(double a, double b, double c) {
  if (a == 0.0) {
    if (b == 0.0) return std::nullopt;
    return std::pair{-c / b, -c / b};
  }
  const double discriminant = b * b - 4.0 * a * c;
  if (discriminant < 0.0) return std::nullopt;
  const double q = -0.5 * (b + std::copysign(std::sqrt(discriminant), b));
  double t0 = q / a, t1 = q != 0.0 ? c / q : t0;
  if (t0 > t1) std::swap(t0, t1);
  return std::pair{t0, t1};
}

std::optional<std::pair<double, double>> intersect(std::pair<double, double> a,
                                                   std::pair<double, double> b) {
  const double t0 = std::max(a.first, b.first), t1 = std::min(a.second, b.second);
  if (!(t0 < t1)) return std::nullopt;
  return std::pair{t0, t1};
}

// Where the line is between two heights.
std::optional<std::pair<double, double>> slab(double origin_z, double direction_z, double z0,
                                              double z1) {
  if (direction_z == 0.0) {
    if (origin_z < z0 || origin_z > z1) return std::nullopt;
    return std::pair{-infinity, infinity};
  }
  double t0 = (z0 - origin_z) / direction_z, t1 = (z1 - origin_z) / direction_z;
  if (t0 > t1) std::swap(t0, t1);
  return std::pair{t0, t1};
}

}  // namespace

double crown_volume_m3(CrownShape shape, double radius_m, double half_height_m) {
  const double pi = std::numbers::pi;
  if (shape == CrownShape::cone) return pi * radius_m * radius_m * (2.0 * half_height_m) / 3.0;
  return 4.0 / 3.0 * pi * radius_m * radius_m * half_height_m;
}

std::optional<std::pair<double, double>> crown_interval(const Crown& crown, const Vec3& origin,
                                                        const Vec3& direction) {
  return CrownCrossing(crown).interval(origin, direction);
}

CrownCrossing::CrownCrossing(const Crown& crown) : cone_(crown.shape == CrownShape::cone) {
  const double r = crown.radius_m, h = crown.half_height_m;
  if (cone_) {
    centre_ = crown.base_m + Vec3{0.0, 0.0, 2.0 * h};
    const double k = r / (2.0 * h);
    slope_sq_ = k * k;
    base_z_ = crown.base_m[2];
  } else {
    centre_ = crown.base_m + Vec3{0.0, 0.0, h};
    inverse_axes_ = {1.0 / r, 1.0 / r, 1.0 / h};
  }
}

std::optional<std::pair<double, double>> CrownCrossing::interval(const Vec3& origin,
                                                                 const Vec3& direction) const {
  if (cone_) {
    // Inside: x^2 + y^2 <= k^2 (z_apex - z)^2, between the base and the apex.
    const double k2 = slope_sq_;
    const Vec3 o = origin - centre_;
    const double a = direction[0] * direction[0] + direction[1] * direction[1] -
                     k2 * direction[2] * direction[2];
    const double b = 2.0 * (o[0] * direction[0] + o[1] * direction[1] - k2 * o[2] * direction[2]);
    const double c = o[0] * o[0] + o[1] * o[1] - k2 * o[2] * o[2];
    const auto height = slab(origin[2], direction[2], base_z_, centre_[2]);
    if (!height) return std::nullopt;
    if (a == 0.0) {  // a line parallel to the cone's side: f = b t + c
      if (b == 0.0) return c <= 0.0 ? height : std::nullopt;
      return intersect(b > 0.0 ? std::pair{-infinity, -c / b} : std::pair{-c / b, infinity},
                       *height);
    }
    const auto roots = quadratic_roots(a, b, c);
    if (!roots) return a < 0.0 ? height : std::nullopt;  // a < 0 and no root: inside everywhere
    if (a > 0.0) return intersect(*roots, *height);
    // a < 0: inside outside the roots; below the apex only one side can meet the slab.
    if (auto below = intersect({-infinity, roots->first}, *height)) return below;
    return intersect({roots->second, infinity}, *height);
  }
  // Ellipsoid: scaled to the unit sphere about its centre.
  const Vec3 o{(origin[0] - centre_[0]) * inverse_axes_[0],
               (origin[1] - centre_[1]) * inverse_axes_[1],
               (origin[2] - centre_[2]) * inverse_axes_[2]};
  const Vec3 d{direction[0] * inverse_axes_[0], direction[1] * inverse_axes_[1],
               direction[2] * inverse_axes_[2]};
  return quadratic_roots(dot(d, d), 2.0 * dot(o, d), dot(o, o) - 1.0);
}

}  // namespace glaswave
