// What `glaswave check` prints on success after its first line: what a run of the configuration
// would do, in a few lines a person reads (track, sensor, terrain, vegetation, rays, an estimate
// of the time and memory, the products).
#pragma once

#include <string>

#include "pipeline/config/config.hpp"
#include "pipeline/engine/run.hpp"

namespace glaswave {

// The lines, each "  label: text\n", from the resolved configuration, the track `check`
// planned and the engine's memory estimate. `config_file` names the default output folder.
std::string run_outline(const Config& config, const CheckSummary& summary,
                        const std::string& config_file);

// A rough wall time of a run (s): per shot, a fixed cost plus one per ray that grows with the
// scattering orders over vegetation, divided among `threads`, as the benchmark measured them on
// a 2-core machine (scripts/benchmark): the seed's base case (forest, 10^4 rays, order 8) about
// 65 ms a shot on one thread, bare ground at 10^3 rays about 1 ms, a 19-ray shot 0.3 ms.
double estimated_run_s(double shots, double rays_per_shot, int max_order, bool vegetation,
                       int threads);

}  // namespace glaswave
