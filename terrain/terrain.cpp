// Terrain height fields: the synthetic plane, and the factory that picks a terrain from settings.
#include "terrain/terrain.hpp"

#include <cmath>
#include <numbers>

#include <GeographicLib/LocalCartesian.hpp>

#include "terrain/error.hpp"

namespace glaswave {

struct PlaneTerrain::Frame {
  GeographicLib::LocalCartesian local;
};

PlaneTerrain::PlaneTerrain(const PlaneSettings& plane)
    : origin_(std::make_shared<Frame>(
          Frame{GeographicLib::LocalCartesian(plane.origin_lat_deg, plane.origin_lon_deg, 0.0)})),
      elevation_m_(plane.elevation_m) {
  const double deg = std::numbers::pi / 180.0;
  const double fall_per_m = std::tan(plane.slope_deg * deg);
  // The surface faces the aspect: heights fall along the unit vector (sin A, cos A).
  east_gradient_ = -fall_per_m * std::sin(plane.aspect_deg * deg);
  north_gradient_ = -fall_per_m * std::cos(plane.aspect_deg * deg);
}

double PlaneTerrain::height_m(double lat_deg, double lon_deg) const {
  double east_m = 0.0, north_m = 0.0, up_m = 0.0;
  origin_->local.Forward(lat_deg, lon_deg, 0.0, east_m, north_m, up_m);
  return elevation_m_ + east_gradient_ * east_m + north_gradient_ * north_m;
}

std::unique_ptr<Terrain> make_terrain(const TerrainSettings& settings) {
  if (settings.plane) return std::make_unique<PlaneTerrain>(*settings.plane);
  throw config_error("/terrain/dem", "DEM terrain is not available in this version yet; use terrain.plane");
}

}  // namespace glaswave
