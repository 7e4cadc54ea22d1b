// Terrain height fields: what every terrain does by default, the synthetic plane, and the
// factory that picks a terrain from settings.
#include "terrain/terrain.hpp"

#include <GeographicLib/LocalCartesian.hpp>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/error.hpp"
#include "terrain/dem_terrain.hpp"
#include "terrain/ground_mesh.hpp"

namespace glaswave {

GroundMesh Terrain::mesh(const LocalFrame& frame, double half_size_m, double spacing_m) const {
  return sample_ground_mesh(*this, frame, half_size_m, spacing_m);
}

bool Terrain::has_data(const LocalFrame& frame, double radius_m) const {
  // Rings of samples no further apart than the terrain's detail (at most 64 a ring): a terrain
  // that only answers height queries cannot say more about its holes.
  const int rings =
      std::clamp(static_cast<int>(std::ceil(radius_m / std::max(detail_m(), 1e-3))), 2, 16);
  for (int ring = 0; ring <= rings; ++ring) {
    const double r_m = radius_m * ring / rings;
    const int points = ring == 0
                           ? 1
                           : std::clamp(static_cast<int>(std::ceil(2.0 * std::numbers::pi * r_m /
                                                                   std::max(detail_m(), 1e-3))),
                                        8, 64);
    for (int k = 0; k < points; ++k) {
      const double azimuth = 2.0 * std::numbers::pi * k / points;
      const Geodetic p = frame.to_geodetic({r_m * std::sin(azimuth), r_m * std::cos(azimuth), 0.0});
      if (!std::isfinite(height_m(p.lat_deg, p.lon_deg))) return false;
    }
  }
  return true;
}

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
  return std::make_unique<DemTerrain>(settings);
}

}  // namespace glaswave
