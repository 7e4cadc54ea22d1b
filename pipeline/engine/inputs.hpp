// The run's inputs from the configuration: the terrain opened, the forest grown, the track
// planned on the terrain. The floors below see only their settings; errors about those come out
// here at their JSON paths.
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "canopy/forest.hpp"
#include "footprints/track.hpp"
#include "pipeline/config/config.hpp"
#include "terrain/terrain.hpp"

namespace glaswave {

std::unique_ptr<Terrain> open_terrain(const Config& config);
// Empty over bare ground.
std::optional<Forest> grow_forest(const Config& config);
std::unique_ptr<Track> plan_track(const Config& config, const Terrain& terrain);

// A warning, at the stands' JSON path, when the configuration has stands and no shot falls
// within any of them (their bounding boxes, 0.001 degrees wider): a stands file in the wrong
// place or CRS would otherwise go unnoticed. Empty otherwise. `shots` are footprint centres
// (lat, lon); NaN ones are passed over.
std::optional<std::string> stands_off_track(const Config& config,
                                            const std::vector<std::array<double, 2>>& shots);

}  // namespace glaswave
