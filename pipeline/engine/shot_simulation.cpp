// Simulation of one footprint into a product record.
#include "pipeline/engine/shot_simulation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "footprints/terrain_intersection.hpp"
#include "pipeline/engine/inputs.hpp"
#include "pipeline/products/product_fields.hpp"
#include "pipeline/products/waveform_metrics.hpp"
#include "pipeline/scene/vegetation.hpp"
#include "pipeline/transport/detector.hpp"
#include "pipeline/transport/shot_transport.hpp"
#include "terrain/ground_mesh.hpp"
#include "terrain/roughness.hpp"

namespace glaswave {
namespace {

constexpr int outline_vertices = 36;

// Half-width of the ground patch that every sampled ray lands on: the beam's rays at `angle_rad`
// from its axis traced to the terrain in a few directions, with a margin.
double patch_half_size_m(const Terrain& terrain, const LidarModel& lidar,
                         const Footprint& footprint, const LocalFrame& frame, double angle_rad) {
  const BeamSampler beam(lidar, footprint.beam_ecef);
  double reach_m = footprint.range_m * angle_rad;
  for (int k = 0; k < 8; ++k) {
    const Vec3 direction = beam.direction_at(angle_rad, k * std::numbers::pi / 4.0);
    if (const auto hit = intersect_terrain(terrain, footprint.spacecraft_ecef, direction)) {
      const Vec3 local = frame.local_from_ecef(*hit);
      reach_m = std::max(reach_m, std::hypot(local[0], local[1]));
    }
  }
  return 1.2 * reach_m + 2.0;
}

// The beam's 1/e^2 contour (2 sigma from the axis) traced on the scene, counter-clockwise
// in longitude and latitude, closed.
std::vector<std::array<double, 2>> beam_outline(const Scene& scene, const LidarModel& lidar,
                                                const ShotGeometry& geometry,
                                                const LocalFrame& frame) {
  const BeamSampler beam(lidar, geometry.axis);
  const double angle_rad = std::min(2.0 * lidar.beam_sigma_rad(), 0.5 * lidar.sensor().ifov_rad);
  const double start_height_m = scene.top_m() + 1.0;
  std::vector<std::array<double, 2>> ring;
  for (int k = 0; k < outline_vertices; ++k) {
    const Vec3 direction =
        beam.direction_at(angle_rad, 2.0 * std::numbers::pi * k / outline_vertices);
    const double start_m = (geometry.sensor_m[2] - start_height_m) / -direction[2];
    const Vec3 origin = geometry.sensor_m + start_m * direction;
    const SurfaceHit hit = scene.intersect(origin, direction, 1.0e5);
    if (hit.kind == SurfaceKind::none) continue;
    const Geodetic point = frame.to_geodetic(origin + hit.distance_m * direction);
    ring.push_back({point.lon_deg, point.lat_deg});
  }
  if (ring.size() < 3) return {};
  double twice_area = 0.0;
  for (std::size_t i = 0; i < ring.size(); ++i) {
    const auto& a = ring[i];
    const auto& b = ring[(i + 1) % ring.size()];
    twice_area += a[0] * b[1] - b[0] * a[1];
  }
  if (twice_area < 0.0) std::reverse(ring.begin(), ring.end());
  ring.push_back(ring.front());
  return ring;
}

// Waveform processing as the sensor and detector make it: noise-free waveforms get the
// fraction-of-peak threshold, detected ones the threshold above their noise.
WaveformProcessing waveform_processing(const Config& config) {
  WaveformProcessing processing;
  processing.pulse_sigma_ns = config.sensor.pulse_sigma_ns;
  processing.noise_free = !config.detector.enabled;
  return processing;
}

}  // namespace

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

Detector::Settings detector_settings(const DetectorSettings& detector) {
  Detector::Settings chain;
  chain.background_W = detector.background_W;
  chain.photon_noise = detector.photon_noise;
  chain.quantum_efficiency = detector.quantum_efficiency;
  chain.noise_rms_W = detector.noise_rms_W;
  chain.gain = detector.gain;
  chain.bits = detector.bits;
  chain.saturation_W = detector.saturation_W;
  return chain;
}

// The scene of one shot, built in its footprint's local frame: the ground patch the beam and
// its diffuse light reach and the trees standing on it, as Embree sees them (the scene keeps
// copies of the meshes).
struct ShotSimulator::ShotScene {
  LocalFrame frame;
  ShotGeometry geometry;
  SurfaceOrientation orientation;
  std::unique_ptr<Scene> scene;
};

ShotSimulator::ShotSimulator(const Config& config, const Terrain& terrain)
    : config_(config),
      terrain_(terrain),
      lidar_(lidar_settings(config.sensor)),
      roughness_(std::make_unique<RoughnessField>(config.terrain.roughness, config.seed)) {
  forest_ = grow_forest(config);
  optics_ = scene_optics();
}

ShotSimulator::~ShotSimulator() = default;

void ShotSimulator::check_scene(const Footprint& footprint) const { build_scene(footprint); }

SceneOptics ShotSimulator::scene_optics() const {
  SceneOptics optics;
  optics.soil_reflectance = config_.terrain.soil_reflectance;
  for (std::size_t kind = 0; forest_ && kind < forest_->kinds(); ++kind) {
    const CanopySettings& canopy = forest_->canopy(kind);
    Foliage foliage;
    for (std::size_t band = 0; band < lidar_.band_count(); ++band) {
      foliage.reflectance.push_back(canopy.green_fraction * canopy.leaf_reflectance[band] +
                                    canopy.bark_fraction * canopy.bark_reflectance[band]);
      foliage.transmittance.push_back(canopy.green_fraction * canopy.leaf_transmittance[band]);
    }
    foliage.trunk_reflectance = canopy.bark_reflectance;
    foliage.leaf_angles = &forest_->leaf_angles(kind);
    foliage.leaf_size_m = canopy.leaf_size_m;
    optics.foliage.push_back(foliage);
  }
  return optics;
}

ShotRecord ShotSimulator::simulate(const Footprint& footprint, std::int64_t* ray_queries) const {
  ShotRecord record;
  record.shot_number = footprint.shot_number;
  record.source_shot_number = footprint.source_shot_number;
  record.time_s = footprint.time_s;
  record.sc_lat_deg = footprint.spacecraft.lat_deg;
  record.sc_lon_deg = footprint.spacecraft.lon_deg;
  record.sc_alt_m = footprint.spacecraft.h_m;
  record.off_nadir_deg = footprint.off_nadir_deg;

  if (!has_terrain(footprint)) {
    flag_off_terrain(record, footprint);
    return record;
  }
  record.lat_deg = footprint.ground.lat_deg;
  record.lon_deg = footprint.ground.lon_deg;
  record.elev_m = footprint.ground.h_m;
  record.range_m = footprint.range_m;

  const ShotScene shot = build_scene(footprint);
  record.slope_deg = shot.orientation.slope_deg;
  record.aspect_deg = shot.orientation.aspect_deg;
  // Bin elevations along the beam axis, from the footprint centre.
  const std::vector<double> bin_time_ns = lidar_.bin_time_ns();
  auto elevation_at = [&](double time_ns) {
    const double along_m = 0.5 * speed_of_light_m_s * time_ns * 1e-9;
    return shot.frame.to_geodetic(along_m * shot.geometry.axis).h_m;
  };
  record.elev_bin0_m = elevation_at(bin_time_ns.front());
  record.elev_lastbin_m = elevation_at(bin_time_ns.back());

  const TransportOptions options = transport_options();
  ShotWaveforms waveforms =
      simulate_shot(*shot.scene, lidar_, shot.geometry, optics_, options, footprint.shot_number);
  if (ray_queries) *ray_queries += waveforms.ray_queries + outline_vertices;
  // The Monte Carlo variance weighs the decomposition's tests; it is not a product.
  const std::vector<std::vector<double>> mc_variance_W2 = std::move(waveforms.total_variance_W2);
  record_waveforms(record, std::move(waveforms), footprint.shot_number);
  if (config_.output.metrics)
    process_shot_waveforms(record, config_.sensor.bin_ns, waveform_processing(config_),
                           mc_variance_W2);
  else  // as a flagged shot's: fill
    fill_fields(record, FieldSource::metrics, ProductShape{.bands = lidar_.band_count()});
  // The truth over the footprint, beside the estimates: what the beam really fell on.
  const VegetationTruth truth =
      measure_vegetation(*shot.scene, footprint.range_m * lidar_.beam_sigma_rad());
  record.cover_true = truth.cover;
  record.pai_true = truth.pai;
  record.canopy_height_true_m = truth.canopy_height_m;
  record.reflectance = surface_reflectance(record, footprint.range_m);
  record.footprint_lonlat = beam_outline(*shot.scene, lidar_, shot.geometry, shot.frame);
  return record;
}

std::optional<ShotWaveforms> ShotSimulator::simulate_ray(const Footprint& footprint,
                                                         std::int64_t ray,
                                                         const RayObserver& observer) const {
  if (!has_terrain(footprint)) return std::nullopt;
  const ShotScene shot = build_scene(footprint);
  return glaswave::simulate_ray(*shot.scene, lidar_, shot.geometry, optics_, transport_options(),
                                footprint.shot_number, ray, observer);
}

// A beam over a hole in the DEM or its edge (3 sigma: 99 % of its energy) gives no waveform
// worth having: the shot is flagged like one off the terrain.
bool ShotSimulator::has_terrain(const Footprint& footprint) const {
  const double data_radius_m = 3.0 * footprint.range_m * lidar_.beam_sigma_rad() /
                               std::cos(footprint.off_nadir_deg * std::numbers::pi / 180.0);
  return footprint.on_terrain && terrain_.has_data(LocalFrame(footprint.ground), data_radius_m);
}

TransportOptions ShotSimulator::transport_options() const {
  TransportOptions options;
  options.rays = config_.simulation.rays_per_shot;
  options.max_order = config_.simulation.max_order;
  options.quasi_random = config_.simulation.quasi_random;
  options.per_order = config_.output.per_order;
  options.seed = config_.seed;
  return options;
}

void ShotSimulator::flag_off_terrain(ShotRecord& record, const Footprint& footprint) const {
  record.quality_flag = quality_invalid;
  // The axis met the terrain, yet nodata or the DEM's edge lies under the beam.
  record.quality_reason = footprint.on_terrain ? reason_nodata : reason_off_terrain;
  const std::size_t orders =
      config_.output.per_order ? static_cast<std::size_t>(config_.simulation.max_order) : 0;
  fill_flagged(record, {.bands = lidar_.band_count(),
                        .bins = static_cast<std::size_t>(lidar_.bins()),
                        .orders = orders});
  // The shot keeps a position, as a trajectory's coordinates should: where the beam met the
  // terrain (over nodata), or else where it crosses the ellipsoid; no height when it met none.
  if (footprint.on_terrain) {
    record.lat_deg = footprint.ground.lat_deg;
    record.lon_deg = footprint.ground.lon_deg;
    record.elev_m = footprint.ground.h_m;
    record.range_m = footprint.range_m;
  } else if (const auto t_m =
                 ellipsoid_crossing(footprint.spacecraft_ecef, footprint.beam_ecef, 0.0)) {
    const Geodetic aim = geodetic_from_ecef(footprint.spacecraft_ecef + *t_m * footprint.beam_ecef);
    record.lat_deg = aim.lat_deg;
    record.lon_deg = aim.lon_deg;
  }
}

ShotSimulator::ShotScene ShotSimulator::build_scene(const Footprint& footprint) const {
  ShotScene shot{LocalFrame(footprint.ground), {}, {}, nullptr};
  shot.geometry.sensor_m = shot.frame.local_from_ecef(footprint.spacecraft_ecef);
  shot.geometry.axis = shot.frame.local_direction(footprint.beam_ecef);
  shot.geometry.range_m = footprint.range_m;
  const double beam_sigma_m = footprint.range_m * lidar_.beam_sigma_rad();
  shot.orientation =
      fit_surface_orientation(terrain_, shot.frame, beam_sigma_m, shot.geometry.axis);

  // With vegetation, diffuse light wanders beyond the beam: the ground reaches further out.
  const double vegetation_margin_m = config_.canopy ? 100.0 : 0.0;
  const double half_size_m =
      patch_half_size_m(terrain_, lidar_, footprint, shot.frame, lidar_.max_angle_rad()) +
      vegetation_margin_m;
  // Roughness is subdivided only where the beam is: beyond 4.5 sigma go 4e-5 of the rays.
  const RoughnessField& roughness = *roughness_;
  const double rough_half_size_m =
      roughness.enabled()
          ? patch_half_size_m(terrain_, lidar_, footprint, shot.frame,
                              std::min(lidar_.max_angle_rad(), 4.5 * lidar_.beam_sigma_rad()))
          : 0.0;
  // Roughness too fine to mesh under this beam is refused there, named in /terrain.
  const GroundMesh ground = at_section("/terrain", [&] {
    return build_ground_mesh(terrain_, shot.frame, half_size_m, terrain_.detail_m(), &roughness,
                             rough_half_size_m);
  });
  const Vegetation vegetation =
      forest_ ? build_vegetation(*forest_, terrain_, shot.frame, half_size_m, shot.orientation)
              : Vegetation{};
  shot.scene = std::make_unique<Scene>(device_, ground, vegetation);
  return shot;
}

void ShotSimulator::record_waveforms(ShotRecord& record, ShotWaveforms waveforms,
                                     std::int64_t shot_number) const {
  record.rx_waveform_W = std::move(waveforms.total_W);
  record.rx_waveform_canopy_W = std::move(waveforms.canopy_W);
  record.rx_waveform_ground_W = std::move(waveforms.ground_W);
  record.rx_waveform_order_W = std::move(waveforms.order_W);
  record.rx_energy_J = waveforms.energy_J;
  record.rx_energy_canopy_J = waveforms.canopy_energy_J;
  record.rx_energy_ground_J = waveforms.ground_energy_J;
  if (!config_.detector.enabled) return;
  // The detector turns the received power into the recorded waveform (its canopy and ground
  // parts stay the noise-free truth); rx_energy stays the integral of rx_waveform.
  const double bin_s = config_.sensor.bin_ns * 1e-9;
  const Detector detector(detector_settings(config_.detector), config_.seed);
  for (std::size_t band = 0; band < lidar_.band_count(); ++band) {
    record.rx_waveform_W[band] =
        detector.record(record.rx_waveform_W[band], config_.sensor.bin_ns,
                        config_.sensor.bands[band].wavelength_nm, shot_number, band);
    double sum_W = 0.0;
    for (double p : record.rx_waveform_W[band]) sum_W += p;
    record.rx_energy_J[band] = sum_W * bin_s;
  }
}

std::vector<double> ShotSimulator::surface_reflectance(const ShotRecord& record,
                                                       double range_m) const {
  // The seed's eq. (1): rho = pi E_rec R^2 / (E_t A_T T). E_rec is all of the received energy;
  // from a detected waveform it is what a user would take: the energy above the noise between
  // signal begin and end (energy_tr), as background and noise summed over the whole window
  // would swamp it.
  std::vector<double> reflectance;
  for (std::size_t band = 0; band < lidar_.band_count(); ++band) {
    const Band& b = config_.sensor.bands[band];
    const double received_J =
        config_.detector.enabled ? record.energy_tr_J[band] : record.rx_energy_J[band];
    reflectance.push_back(std::numbers::pi * received_J * range_m * range_m /
                          (b.pulse_energy_mJ * 1e-3 * config_.sensor.telescope_area_m2 *
                           b.atmos_transmission_roundtrip));
  }
  return reflectance;
}

RunInfo ShotSimulator::run_info(std::int64_t shots, const std::string& command_line) const {
  RunInfo info;
  info.command_line = command_line;
  info.config_json = config_.resolved.dump();
  info.seed = config_.seed;
  info.shots = shots;
  for (const Band& band : config_.sensor.bands)
    info.bands.push_back({band.name, band.wavelength_nm});
  info.bin_time_ns = lidar_.bin_time_ns();
  info.tx_time_ns = lidar_.tx_time_ns();
  for (std::size_t band = 0; band < lidar_.band_count(); ++band)
    info.tx_waveform_W.push_back(lidar_.tx_waveform_W(band));
  info.orders = config_.output.per_order ? config_.simulation.max_order : 0;
  return info;
}

}  // namespace glaswave
