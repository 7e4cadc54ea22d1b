// Opening the run's inputs, with errors at their JSON paths.
#include "pipeline/engine/inputs.hpp"

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

}  // namespace glaswave
