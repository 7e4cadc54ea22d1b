// The run's inputs from the configuration: the terrain opened, the forest grown, the track
// planned on the terrain. The floors below see only their settings; errors about those come out
// here at their JSON paths.
#pragma once

#include <memory>
#include <optional>

#include "canopy/forest.hpp"
#include "footprints/track.hpp"
#include "pipeline/config/config.hpp"
#include "terrain/terrain.hpp"

namespace glaswave {

std::unique_ptr<Terrain> open_terrain(const Config& config);
// Empty over bare ground.
std::optional<Forest> grow_forest(const Config& config);
std::unique_ptr<Track> plan_track(const Config& config, const Terrain& terrain);

}  // namespace glaswave
