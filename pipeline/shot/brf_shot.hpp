// `glaswave brf`'s scene and trace: the scene around a footprint built by the shot's scene
// builder (the tile and, beyond its sides, enough for the crowns that reach into it when it is
// periodic, or for the light that wanders out over a DEM), the sun's photons traced through it.
#pragma once

#include "footprints/track.hpp"
#include "pipeline/shot/shot_simulator.hpp"
#include "pipeline/transport/brf_transport.hpp"

namespace glaswave {

struct BrfScene {
  BrfTile tile;
  BuiltScene built;
};

// The scene over the tile of half-width `tile_half_size_m` around the footprint (periodic over
// a plane).
BrfScene build_brf_scene(const ShotSimulator& simulator, const Footprint& footprint,
                         double tile_half_size_m, bool periodic);

// Traces options.photons photons through it on the current TBB arena.
BrfResult trace_brf(const BrfScene& scene, const BrfOptions& options, const BrfProgress& progress);

}  // namespace glaswave
