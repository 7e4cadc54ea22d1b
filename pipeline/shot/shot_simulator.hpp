// One footprint in, one product record out: the footprint's scene built in its local frame
// (SceneBuilder: the terrain's ground and what the VegetationSource grows on it), its returns
// traced by the transport, turned into the record's fields by the Receiver, and the record
// completed with the geolocation, the truth under the beam and the beam's outline. Typed
// settings only: the engine fills them from the configuration.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "footprints/track.hpp"
#include "pipeline/products/shot_record.hpp"
#include "pipeline/shot/receiver.hpp"
#include "pipeline/shot/scene_builder.hpp"
#include "pipeline/shot/stretch_scenes.hpp"
#include "pipeline/shot/vegetation_source.hpp"
#include "pipeline/transport/lidar_model.hpp"
#include "pipeline/transport/ray_event.hpp"
#include "pipeline/transport/shot_transport.hpp"
#include "terrain/terrain.hpp"
#include "terrain/terrain_settings.hpp"

namespace glaswave {

struct ShotSettings {
  LidarSettings lidar;
  TransportOptions transport;            // rays, orders, sampling, per-order output, seed
  std::vector<double> soil_reflectance;  // [band], Lambertian
  RoughnessSettings roughness;
  // Consecutive shots of a beam that share one scene once the simulator follows a track
  // (stretch_scenes.hpp; the photon-counting receiver's 10 kHz); 0: each shot builds its own.
  std::int64_t stretch_shots = 0;
  // Consecutive shots of a beam that share one strip's scene once the simulator follows a track
  // (stretch_scenes.hpp's strips: a waveform receiver's, on any track); 0: none. stretch_shots
  // comes first.
  std::int64_t strip_shots = 0;
  // Whether anything reads the record's fields that the ICESat-2 granules do not (the beam's
  // outline; the ground's slope and aspect, fitted under each beam): false (a photon-counting
  // run writing its granules alone) leaves the outline empty and, where a shot shares its
  // stretch's scene, the slope and aspect fill, and skips their work.
  bool shot_fields_read = true;
  // Whether anything reads the beam's outline (the footprint polygons): false leaves it empty
  // and skips its 36 ray queries, a tenth of a few-ray shot's own work.
  bool outline_read = true;
};

class ShotSimulator {
 public:
  // `vegetation` may be null (bare ground). `terrain` outlives the simulator.
  ShotSimulator(const ShotSettings& settings, const Terrain& terrain,
                std::unique_ptr<VegetationSource> vegetation, std::unique_ptr<Receiver> receiver);
  ~ShotSimulator();

  // Thread-safe; the record depends only on the settings and the footprint. Adds the shot's ray
  // queries to `ray_queries` when given.
  ShotRecord simulate(const Footprint& footprint, std::int64_t* ray_queries = nullptr) const;

  // Ray `ray` of the footprint's shot alone, as it runs in simulate(), its events told to
  // `observer` (--debug-ray): the ray's part of the shot's returns, before the receiver.
  // Nothing for a shot that simulate() flags (no terrain under the beam).
  std::optional<ShotWaveforms> simulate_ray(const Footprint& footprint, std::int64_t ray,
                                            const RayObserver& observer) const;

  // Builds the footprint's scene and drops it: what a shot refuses before tracing (roughness
  // too fine to mesh under the beam), for `check`.
  void check_scene(const Footprint& footprint) const;
  // Reads the vegetation the footprint's scene would hold and refuses its values as a shot
  // does (a voxel grid's missing values under the beam), without building the scene: for
  // `check`, over every footprint it locates.
  void check_vegetation(const Footprint& footprint) const;
  const VegetationSource* vegetation() const { return vegetation_.get(); }

  // The footprints to come are the track's: consecutive shots of a beam share a stretch's scene
  // when settings.stretch_shots asks for it and the scene allows (no roughness, which is meshed
  // only where the beam is; vegetation fixed on the ground), or a strip's when
  // settings.strip_shots does (vegetation fixed on the ground; roughness meshed under each beam,
  // where the terrain's detail is no finer than the roughness's lattice). The track outlives the
  // simulator.
  void share_scenes_along(const Track& track);
  // Whether shots share a stretch's scene (photon counting's: shots of tenths of a millisecond,
  // which the engine hands its threads in large batches), or a strip's (a waveform receiver's:
  // shots of milliseconds, in the usual small batches).
  bool shares_scenes() const { return stretches_ && stretches_->shape() == StretchShape::square; }
  bool shares_strips() const { return stretches_ && stretches_->shape() == StretchShape::strip; }
  // The stretches or strips the shots share, once share_scenes_along chose them; else null.
  const StretchScenes* stretches() const { return stretches_.get(); }

  const LidarModel& lidar() const { return lidar_; }
  const SceneBuilder& scenes() const { return scenes_; }
  const Receiver& receiver() const { return *receiver_; }

 private:
  struct FootprintScene;
  struct ShotScene;
  FootprintScene build_scene(const Footprint& footprint) const;
  ShotScene scene_of(const Footprint& footprint, std::shared_ptr<const StretchScene> stretch) const;
  void flag_off_terrain(ShotRecord& record, const Footprint& footprint) const;
  bool outline_read() const { return settings_.shot_fields_read && settings_.outline_read; }
  void locate(ShotRecord& record, const Footprint& footprint, const ShotScene& shot) const;
  void trace(ShotRecord& record, const Footprint& footprint, const ShotScene& shot,
             std::int64_t* ray_queries) const;

  ShotSettings settings_;
  LidarModel lidar_;
  std::unique_ptr<VegetationSource> vegetation_;
  std::unique_ptr<Receiver> receiver_;
  SceneBuilder scenes_;
  std::unique_ptr<StretchScenes> stretches_;  // when shots share their stretch's scene
};

}  // namespace glaswave
