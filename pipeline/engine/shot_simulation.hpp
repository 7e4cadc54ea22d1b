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
#include "terrain/terrain.hpp"

namespace glaswave {

// The transport's and the detector's settings from the configuration's.
LidarSettings lidar_settings(const SensorSettings& sensor);
Detector::Settings detector_settings(const DetectorSettings& detector);

class ShotSimulator {
 public:
  ShotSimulator(const Config& config, const Terrain& terrain);

  // Thread-safe; the record depends only on the configuration and the footprint.
  ShotRecord simulate(const Footprint& footprint, std::int64_t* ray_queries = nullptr) const;

  // What the products need to know besides the shots.
  RunInfo run_info(std::int64_t shots, const std::string& command_line) const;

  const LidarModel& lidar() const { return lidar_; }

 private:
  const Config& config_;
  const Terrain& terrain_;
  LidarModel lidar_;
  RayDevice device_;
  std::optional<Forest> forest_;  // when there is vegetation
};

}  // namespace glaswave
