// The canopy section's reader, shared by the configuration (`"canopy"`) and the stands file,
// whose features' fields override the scene's canopy keys inside them.
#pragma once

#include <optional>
#include <vector>

#include "canopy/canopy_settings.hpp"
#include "pipeline/config/config.hpp"
#include "pipeline/config/json_reader.hpp"

namespace glaswave {

// The canopy of `root`'s "canopy" object, its per-band optics in the order of `bands`; none (bare
// ground) when the key is absent or null.
std::optional<CanopySettings> read_canopy(JsonReader& root, const std::vector<LidarBand>& bands);

}  // namespace glaswave
