// A local east-north-up frame anchored on a geodetic point (GeographicLib LocalCartesian),
// in double precision: each shot is simulated in the frame of its footprint.
#pragma once

#include <GeographicLib/LocalCartesian.hpp>
#include <array>

#include "core/vec3.hpp"

namespace glaswave {

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

}  // namespace glaswave
