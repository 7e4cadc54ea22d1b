// The run's inputs from the configuration: the terrain opened, the vegetation source made, the
// shot simulator given its typed settings, the track planned on the terrain. The floors below
// see only their settings; errors about those come out here at their JSON paths.
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "footprints/track.hpp"
#include "pipeline/config/config.hpp"
#include "pipeline/shot/shot_simulator.hpp"
#include "terrain/terrain.hpp"

namespace glaswave {

std::unique_ptr<Terrain> open_terrain(const Config& config);
// The shot layer's settings from the configuration's.
ShotSettings shot_settings(const Config& config);
ReceiverSettings receiver_settings(const Config& config);
VegetationSettings vegetation_settings(const Config& config);  // config.canopy must be set
// The configuration's vegetation source (canopy.kind); null over bare ground. Given the run's
// terrain, a point cloud's source takes the ground terrain.point_cloud gridded from it.
std::unique_ptr<VegetationSource> grow_vegetation(const Config& config,
                                                  const Terrain* terrain = nullptr);
// The shot simulator of the configuration, its vegetation grown and its receiver made.
std::unique_ptr<ShotSimulator> make_shot_simulator(const Config& config, const Terrain& terrain);
// Whether a product of the output reads the shots' fields beyond those of the ICESat-2 granules
// (which are made from the photons, the geolocation, the sun and the truth): the waveform
// metrics, the fitted slope and aspect, the beam's outline. shots.nc, the footprints and the
// GEDI and GLAS granules do.
bool products_read_shot_fields(const OutputSettings& output);
// The shot simulator of a run writing the configuration's products: make_shot_simulator's,
// leaving out what none of them reads (a photon-counting run writing its ICESat-2 granules
// alone skips the waveform processing, flagging its shots as that would, the ground fitted
// under each shot of a shared stretch and the beam's outline; a run without the footprint
// polygons skips the outline).
std::unique_ptr<ShotSimulator> make_run_shot_simulator(const Config& config,
                                                       const Terrain& terrain);
// What the products need to know besides the shots.
RunInfo run_info(const Config& config, const ShotSimulator& simulator, std::int64_t shots,
                 const std::string& command_line);
// The planned track, and what its shot numbers allow: GLAS granules (output.glah01, glah14)
// number a shot by a 4-byte record index, i_rec_ndx (the GLAH dictionary's type), so a track
// whose shot numbers pass 40 x (2^31 - 1) (a GEDI granule's) is refused at the key (a config
// error), where each shot became the same record.
std::unique_ptr<Track> plan_track(const Config& config, const Terrain& terrain);

// A warning, at the stands' JSON path, when the configuration has stands and no shot falls
// within any of them (their bounding boxes, 0.001 degrees wider): a stands file in the wrong
// place or CRS would otherwise go unnoticed. Empty otherwise. `shots` are footprint centres
// (lat, lon); NaN ones are passed over.
std::optional<std::string> stands_off_track(const Config& config,
                                            const std::vector<std::array<double, 2>>& shots);

// A warning, at the source's file's JSON path, when the vegetation has plants a file placed (a
// crowns file's crowns, facet trees, a voxel grid's or point cloud's corners) and no footprint
// centre (lat, lon) lies within 100 m of their bounding box widened by the largest crown: crowns
// placed far away (x,y from another origin, latitude and longitude swapped) would otherwise leave
// every shot over bare ground without a word. Empty otherwise, and when no footprint is on the
// terrain.
std::optional<std::string> crowns_off_track(const Config& config,
                                            const VegetationSource* vegetation,
                                            const std::vector<std::array<double, 2>>& shots);

}  // namespace glaswave
