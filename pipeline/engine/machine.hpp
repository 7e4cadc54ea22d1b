// What the machine gives a run, and what a run will take of it: the threads of a process, and
// the memory a run or `brf` will hold, estimated from the configuration before anything is
// allocated and refused when the machine (or the cgroup, or ulimit -v) has less, at the key that
// makes it large.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "core/error.hpp"
#include "pipeline/config/config.hpp"

namespace glaswave {

class Terrain;
struct Footprint;
class ShotSimulator;
class Track;

// Threads of this process: `threads` (0: its share of the machine's cores, the cores divided
// among the run's processes on this machine), never more than the cores.
int threads_of_process(int threads, int processes_here);

// What a run will hold in memory, estimated from the configuration before anything is
// allocated: each thread simulates a shot, holding its scene (the vegetation and ground under
// the field of view, as its source's region_bytes says) and its waveforms' tallies; the
// vegetation source holds its own once (a point cloud's voxelisation, facet models).
// What glaswave holds before any scene: its libraries (GDAL, PROJ, HDF5, NetCDF, Embree, TBB),
// Embree's device, the threads' stacks, the writers' buffers. A run of one shot over bare ground
// peaked at 57.2 MiB (`/usr/bin/time -v`, Debian 12's build), of which its scenes and waveforms
// are 4.5 MiB; a `brf` of one photon over HET02's turbid spheres 61.9 MiB. Without it the estimate
// of a small scene was 7x low (issue 41: a turbid HET03 run, 8.9 MiB for 59.7 measured).
inline constexpr double program_resident_bytes = 52.0 * 1048576.0;

// The scenes a run's shots share along its track (stretch_scenes.hpp's strips: a waveform
// pass's), as its simulator plans them once it follows the track: the memory estimate counts
// these in place of a shot's own scene a thread.
// A strip's ground: the terrain's mesh cut to it, and the roughness's lattice under its beams
// (two triangles a cell of its grids).
struct StripGround {
  double terrain_triangles = 0.0, rough_triangles = 0.0;
};
struct SharedScenes {
  std::int64_t shots = 0;        // a strip's shots
  double held = 0.0;             // strips kept at once: StretchScenes::kept(), at most the track's
  double length_m = 0.0;         // the largest planned strip's rectangle: along the track
  double width_m = 0.0;          // ... and across it
  double vegetation_side_m = 0;  // a square of the ground its vegetation grows on: the rectangle's
                                 // area where the source keeps to it, else the square holding it
  StripGround ground;
};
// None where the simulator (after share_scenes_along) shares no strips.
std::optional<SharedScenes> shared_scenes(const ShotSimulator& simulator, const Track& track);

// What a ground triangle of a strip's scene takes: its vertex and index (floats, 32-bit
// indices), Embree's copy and hierarchy of them, the roughened mesh's working copies. Measured:
// a GEDI pass's peak resident memory with roughness (0.2 m, 3 m) less without, over its 5 strips
// kept of 70,000 triangles each: 113 bytes a triangle on one thread, 130 on two.
inline constexpr double ground_triangle_bytes = 120.0;
// What a triangle of the roughness's lattice takes, handed to Embree as grids (issue 39): its
// node, Embree's grid and its hierarchy over 2 x 2 cells, the roughening's working copies.
// Measured as above on the GEDI demo pass (its DEM and forest, 5 strips kept): 16 and 18 bytes a
// triangle on one and two threads at 3 m correlation (71,000 a strip), 25 and 30 at 1.5 m
// (284,000 a strip, the working copies larger).
inline constexpr double rough_triangle_bytes = 32.0;

struct RunMemory {
  double scene_half_size_m = 0.0;  // half the side of the ground patch a shot's rays can reach
  double trees = 0.0;              // a forest's trees on it (the densest stand's density)
  double tree_bytes = 0.0;         // of one, where the source counts its scene in trees; else 0
  double scene_bytes = 0.0;        // its vegetation's (a DEM's mesh is capped: ground_mesh.cpp)
  double source_bytes = 0.0;       // what the vegetation source holds once (a point cloud, models)
  std::string vegetation;          // the canopy's kind; empty for bare ground
  double waveform_bytes = 0.0;     // the tallies of a shot's waveforms
  double granule_bytes = 0.0;      // ATL03's and ATL08's photons and records, held to the end
  int threads = 1;                 // the cores this process may use: a run's default
  // Where shots share strips: their shots, and the strips' scenes held at once, each of
  // scene_bytes (its vegetation) and ground_bytes (its ground); else a shot's own scene a
  // thread (scenes = threads, no ground counted).
  std::optional<SharedScenes> strips;
  double scenes = 1.0;
  double ground_bytes = 0.0;
  double program_bytes = 0.0;  // the program's own (program_resident_bytes)
  // program + source + granules + scenes x (scene + ground) + threads x waveforms
  double bytes = 0.0;
  double available_bytes = 0.0;  // the machine's memory (or the cgroup's limit when lower)
  std::string place;             // the key that makes it large, when it is too large
};
// With `shared`, the scenes the run's shots share (shared_scenes) are counted in place of a
// shot's own.
RunMemory estimate_run_memory(const Config& config, const SharedScenes* shared = nullptr);

// Refuses a run that would hold more memory than this process may have, at the key that makes
// it large.
void check_run_memory(const RunMemory& memory);

// What `run` needs beyond a configuration that simulates: no more memory than the machine has
// (estimate_run_memory), then what it needs of its outputs (check_outputs). `check` asks the
// same, so that the two accept exactly the same configurations.
void check_run(const Config& config);

// What `glaswave brf` will hold in memory, estimated as for a run: one scene (shared by the
// threads), the vegetation on its tile and beyond its sides (5 m over a periodic plane, 100 m
// over a DEM) with what its source holds, and scene.tif's bands of doubles.
struct BrfMemory {
  double pixels = 0.0;         // scene.tif's side: brf.scene_size_m in whole pixels
  double scene_side_m = 0.0;   // the ground the scene is built over
  double trees = 0.0;          // a forest's on it, at the densest stand's density
  double tree_bytes = 0.0;     // of one, where the source counts its scene in trees; else 0
  double scene_bytes = 0.0;    // its vegetation's, and what the vegetation source holds once
  std::string vegetation;      // the canopy's kind; empty for bare ground
  double image_bytes = 0.0;    // scene.tif's bands, brf_image_copies times
  double program_bytes = 0.0;  // the program's own (program_resident_bytes)
  double bytes = 0.0;          // program + scene + image
  double available_bytes = 0.0;
  std::string place;  // the key that makes it large, when it is too large
};
BrfMemory estimate_brf_memory(const Config& config);

// What `brf` refuses before tracing anything: scene.tif wider than brf_image_pixels, or more
// memory than this process may have (estimate_brf_memory), at the key that makes it large.
// `check` asks the same.
void check_brf(const Config& config);

// Over a DEM (a plane's tile is periodic, and the plane everywhere), brf's tile of
// brf.scene_size_m about the first footprint must lie on the terrain's data: the config error at
// /brf/scene_size_m where it does not, since the sunlight falling where there is no ground would
// be lost (a 300 m tile over a 200 m point cloud's ground gave albedo 0.112 for 0.251); nothing
// where it does. brf throws it; check, whose configuration may be meant for run alone, warns.
std::optional<Error> brf_tile_error(const Config& config, const Terrain& terrain,
                                    const Footprint& footprint);

}  // namespace glaswave
