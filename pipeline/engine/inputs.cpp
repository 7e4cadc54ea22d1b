// Opening the run's inputs, with errors at their JSON paths.
#include "pipeline/engine/inputs.hpp"

#include <algorithm>

namespace glaswave {

std::unique_ptr<Terrain> open_terrain(const Config& config) {
  return at_section("/terrain", [&] { return make_terrain(config.terrain); });
}

LidarSettings lidar_settings(const SensorSettings& sensor) {
  LidarSettings lidar;
  lidar.pulse_sigma_ns = sensor.pulse_sigma_ns;
  lidar.divergence_sigma_rad = sensor.divergence_sigma_rad;
  lidar.ifov_rad = sensor.ifov_rad;
  lidar.telescope_area_m2 = sensor.telescope_area_m2;
  lidar.bin_ns = sensor.bin_ns;
  lidar.bins = sensor.bins;
  for (const Band& band : sensor.bands)
    lidar.bands.push_back(
        {band.wavelength_nm, band.pulse_energy_mJ, band.atmos_transmission_roundtrip});
  return lidar;
}

ShotSettings shot_settings(const Config& config) {
  ShotSettings settings;
  settings.lidar = lidar_settings(config.sensor);
  settings.transport.rays = config.simulation.rays_per_shot;
  settings.transport.max_order = config.simulation.max_order;
  settings.transport.quasi_random = config.simulation.quasi_random;
  settings.transport.per_order = config.output.per_order;
  settings.transport.seed = config.seed;
  settings.soil_reflectance = config.terrain.soil_reflectance;
  settings.roughness = config.terrain.roughness;
  return settings;
}

ReceiverSettings receiver_settings(const Config& config) {
  ReceiverSettings settings;
  settings.kind = config.detector.kind;
  settings.lidar = lidar_settings(config.sensor);
  settings.metrics = config.output.metrics;
  settings.seed = config.seed;
  if (!config.detector.enabled) return settings;
  const DetectorSettings& detector = config.detector;
  Detector::Settings& chain = settings.detector.emplace();
  chain.background_W = detector.background_W;
  chain.photon_noise = detector.photon_noise;
  chain.quantum_efficiency = detector.quantum_efficiency;
  chain.noise_rms_W = detector.noise_rms_W;
  chain.gain = detector.gain;
  chain.bits = detector.bits;
  chain.saturation_W = detector.saturation_W;
  return settings;
}

VegetationSettings vegetation_settings(const Config& config) {
  return {*config.canopy, config.seed, config.terrain.plane};
}

std::unique_ptr<VegetationSource> grow_vegetation(const Config& config) {
  if (!config.canopy) return nullptr;
  return at_section("/canopy", [&] { return make_vegetation_source(vegetation_settings(config)); });
}

std::unique_ptr<ShotSimulator> make_shot_simulator(const Config& config, const Terrain& terrain) {
  std::unique_ptr<VegetationSource> vegetation = grow_vegetation(config);
  std::unique_ptr<Receiver> receiver =
      at_section("/detector", [&] { return make_receiver(receiver_settings(config)); });
  return std::make_unique<ShotSimulator>(shot_settings(config), terrain, std::move(vegetation),
                                         std::move(receiver));
}

RunInfo run_info(const Config& config, const ShotSimulator& simulator, std::int64_t shots,
                 const std::string& command_line) {
  const LidarModel& lidar = simulator.lidar();
  RunInfo info;
  info.command_line = command_line;
  info.config_json = config.resolved.dump();
  info.seed = config.seed;
  info.shots = shots;
  for (const Band& band : config.sensor.bands)
    info.bands.push_back({band.name, band.wavelength_nm});
  info.bin_time_ns = lidar.bin_time_ns();
  info.tx_time_ns = lidar.tx_time_ns();
  for (std::size_t band = 0; band < lidar.band_count(); ++band)
    info.tx_waveform_W.push_back(lidar.tx_waveform_W(band));
  info.orders = config.output.per_order ? config.simulation.max_order : 0;
  info.photon_events = simulator.receiver().photon_events();
  return info;
}

std::unique_ptr<Track> plan_track(const Config& config, const Terrain& terrain) {
  return at_section("/track", [&] { return std::make_unique<Track>(config.track, terrain); });
}

std::optional<std::string> stands_off_track(const Config& config,
                                            const std::vector<std::array<double, 2>>& shots) {
  if (!config.canopy || config.canopy->stand_areas.empty()) return std::nullopt;
  constexpr double margin_deg = 0.001;  // about 100 m: a beam and its diffuse light
  const auto& stands = config.canopy->stand_areas;
  for (const StandArea& stand : stands) {
    double lat_min = 90.0, lat_max = -90.0, lon_min = 360.0, lon_max = -360.0;
    for (const auto& ring : stand.rings)
      for (const auto& [lon, lat] : ring) {
        lat_min = std::min(lat_min, lat), lat_max = std::max(lat_max, lat);
        lon_min = std::min(lon_min, lon), lon_max = std::max(lon_max, lon);
      }
    for (const auto& [lat, lon] : shots)
      if (lat >= lat_min - margin_deg && lat <= lat_max + margin_deg &&
          lon >= lon_min - margin_deg && lon <= lon_max + margin_deg)
        return std::nullopt;
  }
  return "/canopy/stands: none of the " + std::to_string(stands.size()) + " stands of " +
         config.canopy->stands + " lies under any of the " + std::to_string(shots.size()) +
         " shots; check where the file puts them (its CRS)";
}

}  // namespace glaswave
