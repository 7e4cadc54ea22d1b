// Local east-north-up frames and WGS84 conversions.
#include "terrain/local_frame.hpp"

#include <GeographicLib/Geocentric.hpp>
#include <cmath>
#include <numbers>

namespace glaswave {

LocalFrame::LocalFrame(const Geodetic& origin)
    : origin_(origin),
      cartesian_(origin.lat_deg, origin.lon_deg, origin.h_m),
      origin_ecef_(ecef_from_geodetic(origin)),
      axes_(enu_axes(origin.lat_deg, origin.lon_deg)) {}

Vec3 LocalFrame::to_local(const Geodetic& point) const {
  Vec3 local{};
  cartesian_.Forward(point.lat_deg, point.lon_deg, point.h_m, local[0], local[1], local[2]);
  return local;
}

Geodetic LocalFrame::to_geodetic(const Vec3& local) const {
  Geodetic point;
  cartesian_.Reverse(local[0], local[1], local[2], point.lat_deg, point.lon_deg, point.h_m);
  return point;
}

Vec3 LocalFrame::local_from_ecef(const Vec3& ecef) const {
  return local_direction(ecef - origin_ecef_);
}

Vec3 LocalFrame::ecef_from_local(const Vec3& local) const {
  return origin_ecef_ + ecef_direction(local);
}

Vec3 LocalFrame::local_direction(const Vec3& ecef_direction) const {
  return {dot(axes_[0], ecef_direction), dot(axes_[1], ecef_direction),
          dot(axes_[2], ecef_direction)};
}

Vec3 LocalFrame::ecef_direction(const Vec3& local_direction) const {
  return local_direction[0] * axes_[0] + local_direction[1] * axes_[1] +
         local_direction[2] * axes_[2];
}

Vec3 ecef_from_geodetic(const Geodetic& point) {
  Vec3 ecef{};
  GeographicLib::Geocentric::WGS84().Forward(point.lat_deg, point.lon_deg, point.h_m, ecef[0],
                                             ecef[1], ecef[2]);
  return ecef;
}

Geodetic geodetic_from_ecef(const Vec3& ecef) {
  Geodetic point;
  GeographicLib::Geocentric::WGS84().Reverse(ecef[0], ecef[1], ecef[2], point.lat_deg,
                                             point.lon_deg, point.h_m);
  return point;
}

std::array<Vec3, 3> enu_axes(double lat_deg, double lon_deg) {
  const double deg = std::numbers::pi / 180.0;
  const double sin_lat = std::sin(lat_deg * deg), cos_lat = std::cos(lat_deg * deg);
  const double sin_lon = std::sin(lon_deg * deg), cos_lon = std::cos(lon_deg * deg);
  return {Vec3{-sin_lon, cos_lon, 0.0}, Vec3{-sin_lat * cos_lon, -sin_lat * sin_lon, cos_lat},
          Vec3{cos_lat * cos_lon, cos_lat * sin_lon, sin_lat}};
}

}  // namespace glaswave
