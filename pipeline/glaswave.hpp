// glaswave as a library: the headers a program needs to configure a run, build its terrain and
// track, simulate shots and read their records, or run the whole engine as the command does.
// Installed as <glaswave/glaswave.hpp>; see examples/one_shot.cpp.
#pragma once

#include "core/error.hpp"              // Error: every failure, with its place and kind
#include "footprints/track.hpp"        // Track, Footprint: where each shot meets the terrain
#include "pipeline/config/config.hpp"  // parse_config, load_config, Config
#include "pipeline/engine/inputs.hpp"  // open_terrain, plan_track, make_shot_simulator: the inputs, errors at JSON paths
#include "pipeline/engine/machine.hpp"         // check_run, check_brf: the memory a run will hold
#include "pipeline/engine/run.hpp"             // run_simulation, check_inputs: the engine
#include "pipeline/products/shot_record.hpp"   // ShotRecord: a shot's waveforms and metrics
#include "pipeline/shot/shot_simulator.hpp"    // ShotSimulator: one footprint, one record
#include "pipeline/transport/lidar_model.hpp"  // LidarModel: the sensor, bins and pulse
#include "terrain/terrain.hpp"                 // make_terrain, Terrain
