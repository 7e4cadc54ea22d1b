// A local east-north-up frame anchored on a geodetic point (GeographicLib LocalCartesian),
// in double precision: each shot is simulated in the frame of its footprint.
#pragma once

#include <GeographicLib/LocalCartesian.hpp>
#include <array>

namespace glaswave {

using Vec3 = std::array<double, 3>;

struct Geodetic {
  double lat_deg = 0.0;
  double lon_deg = 0.0;
  double h_m = 0.0;  // above the WGS84 ellipsoid
};

class LocalFrame {
 public:
  explicit LocalFrame(const Geodetic& origin);

  const Geodetic& origin() const { return origin_; }
  Vec3 to_local(const Geodetic& point) const;
  Geodetic to_geodetic(const Vec3& local) const;
  // Earth-centred Earth-fixed position <-> local position.
  Vec3 local_from_ecef(const Vec3& ecef) const;
  Vec3 ecef_from_local(const Vec3& local) const;
  // Directions (no translation).
  Vec3 local_direction(const Vec3& ecef_direction) const;
  Vec3 ecef_direction(const Vec3& local_direction) const;

 private:
  Geodetic origin_;
  GeographicLib::LocalCartesian cartesian_;
  Vec3 origin_ecef_;
  std::array<Vec3, 3> axes_;  // east, north, up in ECEF
};

// ECEF <-> geodetic on WGS84.
Vec3 ecef_from_geodetic(const Geodetic& point);
Geodetic geodetic_from_ecef(const Vec3& ecef);

// East, north and up unit vectors (ECEF) at a geodetic position.
std::array<Vec3, 3> enu_axes(double lat_deg, double lon_deg);

inline double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Vec3 operator+(const Vec3& a, const Vec3& b) {
  return {a[0] + b[0], a[1] + b[1], a[2] + b[2]};
}
inline Vec3 operator-(const Vec3& a, const Vec3& b) {
  return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
inline Vec3 operator*(double s, const Vec3& a) { return {s * a[0], s * a[1], s * a[2]}; }
Vec3 cross(const Vec3& a, const Vec3& b);
double norm(const Vec3& a);
Vec3 normalized(const Vec3& a);

}  // namespace glaswave
