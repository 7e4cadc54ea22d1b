// `glaswave brf`'s scene and trace: the scene around a footprint built by the shot's scene
// builder (the tile and, beyond its sides, enough for the crowns that reach into it when it is
// periodic, or for the light that wanders out over a DEM), the sun's photons traced through it.
#pragma once

#include <array>
#include <optional>

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

// A point of the square tile of half-width `tile_half_size_m` about the frame's origin (metres
// east and north) where the terrain has no ground (off a DEM's data, or over its nodata), looked
// for at the terrain's detail, at most 257 points a side; none where the ground covers the tile.
// Sunlight falling there would pass through the scene unseen: brf refuses such a tile.
std::optional<std::array<double, 2>> tile_off_terrain(const Terrain& terrain,
                                                      const LocalFrame& frame,
                                                      double tile_half_size_m);

// Traces options.photons photons through it on the current TBB arena.
BrfResult trace_brf(const BrfScene& scene, const BrfOptions& options, const BrfProgress& progress);

}  // namespace glaswave
