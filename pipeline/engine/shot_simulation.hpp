// One footprint in, one product record out: the shot's scene is built in its local frame,
// its waveforms simulated, and the record filled with geolocation and derived quantities.
#pragma once

#include <memory>

#include "canopy/forest.hpp"
#include "footprints/track.hpp"
#include "pipeline/config/config.hpp"
#include "pipeline/products/shot_record.hpp"
#include "pipeline/scene/scene.hpp"
#include "pipeline/transport/detector.hpp"
#include "pipeline/transport/lidar_model.hpp"
#include "pipeline/transport/shot_transport.hpp"
#include "terrain/terrain.hpp"

namespace glaswave {

class RoughnessField;

// The transport's and the detector's settings from the configuration's.
LidarSettings lidar_settings(const SensorSettings& sensor);
Detector::Settings detector_settings(const DetectorSettings& detector);

class ShotSimulator {
 public:
  ShotSimulator(const Config& config, const Terrain& terrain);
  ~ShotSimulator();

  // Thread-safe; the record depends only on the configuration and the footprint.
  ShotRecord simulate(const Footprint& footprint, std::int64_t* ray_queries = nullptr) const;

  // Ray `ray` of the footprint's shot alone, as it runs in simulate(), its events told to
  // `observer` (--debug-ray): the ray's part of the shot's waveforms, before the detector.
  // Nothing for a shot that simulate() flags (no terrain under the beam).
  std::optional<ShotWaveforms> simulate_ray(const Footprint& footprint, std::int64_t ray,
                                            const RayObserver& observer) const;

  // Builds the footprint's scene and drops it: what a shot refuses before tracing (roughness
  // too fine to mesh under the beam), for `check`.
  void check_scene(const Footprint& footprint) const;

  // What the products need to know besides the shots.
  RunInfo run_info(std::int64_t shots, const std::string& command_line) const;

  const LidarModel& lidar() const { return lidar_; }
  // The scene's optics and its forest (empty over bare ground), as every shot sees them.
  const SceneOptics& optics() const { return optics_; }
  const std::optional<Forest>& forest() const { return forest_; }

 private:
  struct ShotScene;
  SceneOptics scene_optics() const;
  bool has_terrain(const Footprint& footprint) const;
  TransportOptions transport_options() const;
  // The steps of simulate(), in their order.
  void flag_off_terrain(ShotRecord& record, const Footprint& footprint) const;
  ShotScene build_scene(const Footprint& footprint) const;
  void record_waveforms(ShotRecord& record, ShotWaveforms waveforms,
                        std::int64_t shot_number) const;
  std::vector<double> surface_reflectance(const ShotRecord& record, double range_m) const;

  const Config& config_;
  const Terrain& terrain_;
  LidarModel lidar_;
  RayDevice device_;
  // The same for every shot: made once (its lattices' kernels), not per shot.
  std::unique_ptr<RoughnessField> roughness_;
  std::optional<Forest> forest_;  // when there is vegetation
  SceneOptics optics_;            // the same for every shot
};

}  // namespace glaswave
