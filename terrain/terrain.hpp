// The ground as a height field: heights above the WGS84 ellipsoid by geodetic position,
// from a DEM or a synthetic plane.
#pragma once

#include <memory>

#include "terrain/terrain_settings.hpp"

namespace glaswave {

class Terrain {
 public:
  virtual ~Terrain() = default;

  // Height above the WGS84 ellipsoid (m) at a geodetic position, NaN where there is no data.
  virtual double height_m(double lat_deg, double lon_deg) const = 0;

  // The spacing (m) at which the terrain carries detail: a mesh finer than this adds nothing.
  virtual double detail_m() const = 0;
};

// A tilted plane: heights fall by tan(slope) per metre toward the aspect, measured in the
// east-north plane of the origin's local tangent frame.
class PlaneTerrain final : public Terrain {
 public:
  explicit PlaneTerrain(const PlaneSettings& plane);
  double height_m(double lat_deg, double lon_deg) const override;
  double detail_m() const override { return 1.0e9; }

 private:
  struct Frame;
  std::shared_ptr<const Frame> origin_;  // GeographicLib frame at the origin
  double elevation_m_;
  double east_gradient_;   // dh/de
  double north_gradient_;  // dh/dn
};

// The terrain the settings describe.
std::unique_ptr<Terrain> make_terrain(const TerrainSettings& settings);

}  // namespace glaswave
