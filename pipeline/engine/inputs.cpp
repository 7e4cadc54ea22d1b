// Opening the run's inputs, with errors at their JSON paths.
#include "pipeline/engine/inputs.hpp"

#include <algorithm>

namespace glaswave {

std::unique_ptr<Terrain> open_terrain(const Config& config) {
  return at_section("/terrain", [&] { return make_terrain(config.terrain); });
}

std::optional<Forest> grow_forest(const Config& config) {
  if (!config.canopy) return std::nullopt;
  return at_section("/canopy", [&] {
    return std::optional<Forest>(std::in_place, *config.canopy, config.seed, config.terrain.plane);
  });
}

std::unique_ptr<Track> plan_track(const Config& config, const Terrain& terrain) {
  return at_section("/track", [&] { return std::make_unique<Track>(config.track, terrain); });
}

std::optional<std::string> stands_off_track(const Config& config,
                                            const std::vector<std::array<double, 2>>& shots) {
  if (!config.canopy || config.canopy->stand_areas.empty()) return std::nullopt;
  constexpr double margin_deg = 0.001;  // about 100 m: a beam and its diffuse light
  const auto& stands = config.canopy->stand_areas;
  for (const StandArea& stand : stands) {
    double lat_min = 90.0, lat_max = -90.0, lon_min = 360.0, lon_max = -360.0;
    for (const auto& ring : stand.rings)
      for (const auto& [lon, lat] : ring) {
        lat_min = std::min(lat_min, lat), lat_max = std::max(lat_max, lat);
        lon_min = std::min(lon_min, lon), lon_max = std::max(lon_max, lon);
      }
    for (const auto& [lat, lon] : shots)
      if (lat >= lat_min - margin_deg && lat <= lat_max + margin_deg &&
          lon >= lon_min - margin_deg && lon <= lon_max + margin_deg)
        return std::nullopt;
  }
  return "/canopy/stands: none of the " + std::to_string(stands.size()) + " stands of " +
         config.canopy->stands + " lies under any of the " + std::to_string(shots.size()) +
         " shots; check where the file puts them (its CRS)";
}

}  // namespace glaswave
