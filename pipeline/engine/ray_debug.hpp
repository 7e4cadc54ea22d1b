// `glaswave run CONFIG --debug-ray SHOT:RAY`: one ray of one shot re-run alone, exactly as it
// runs inside `glaswave run` (a ray's random numbers depend only on (seed, shot, ray)), each
// event of its paths told to an observer. The first tool to reach for when a waveform looks
// wrong: where did this ray go, what did it meet, what did it score, and in which bin.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "pipeline/config/config.hpp"
#include "pipeline/shot/shot_simulator.hpp"

namespace glaswave {

struct RayDebug {
  std::int64_t shot_number = 0, ray = 0;
  std::int64_t rays_per_shot = 0;
  std::vector<std::string> band_names;
  ShotWaveforms waveforms;  // the ray's part of its shot's waveforms
};

// Plans the configuration's track, builds shot `shot_number`'s scene as a run does and traces
// ray `ray` of it alone. Throws Error (place "--debug-ray") for a shot number outside the
// track, a shot a run would flag (its beam off the terrain), or a ray outside the shot's rays.
RayDebug debug_ray(const Config& config, std::int64_t shot_number, std::int64_t ray,
                   const RayObserver& observer);

}  // namespace glaswave
