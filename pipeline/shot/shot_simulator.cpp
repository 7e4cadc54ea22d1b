// Simulation of one footprint into a product record.
#include "pipeline/shot/shot_simulator.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "footprints/solar_position.hpp"
#include "footprints/terrain_intersection.hpp"
#include "pipeline/products/product_fields.hpp"
#include "pipeline/shot/footprint_geometry.hpp"
#include "pipeline/transport/scattering.hpp"

namespace glaswave {

// The scene of one shot, built in its footprint's local frame: the ground patch the beam and
// its diffuse light reach and what grows on it, as Embree sees them (the scene keeps copies of
// the meshes).
struct ShotSimulator::FootprintScene {
  FootprintFrame where;
  BuiltScene built;
};

// What a shot is traced through: its own scene, or its stretch's. The shot's geometry is in the
// scene's frame, where its footprint centre lies at centre_m (the origin of its own); the
// ground's orientation is the footprint's, fitted in its own frame.
struct ShotSimulator::ShotScene {
  std::optional<FootprintScene> own;
  std::shared_ptr<const StretchScene> stretch;
  ShotGeometry geometry;
  Vec3 centre_m{};
  SurfaceOrientation orientation;

  const LocalFrame& frame() const { return stretch ? stretch->frame : own->where.frame; }
  const BuiltScene& built() const { return stretch ? stretch->built : own->built; }
  // The point `along_m` down the beam axis from the footprint centre.
  Geodetic on_axis(double along_m) const {
    return frame().to_geodetic(centre_m + along_m * geometry.axis);
  }
};

ShotSimulator::ShotSimulator(const ShotSettings& settings, const Terrain& terrain,
                             std::unique_ptr<VegetationSource> vegetation,
                             std::unique_ptr<Receiver> receiver)
    : settings_(settings),
      lidar_(settings.lidar),
      vegetation_(std::move(vegetation)),
      receiver_(std::move(receiver)),
      scenes_(terrain, settings.roughness, settings.transport.seed, settings.soil_reflectance,
              vegetation_.get(), lidar_.band_count()) {
  const Receiver::ReturnsForm form = receiver_->returns_form();
  settings_.transport.power_waveforms = form.power;
  settings_.transport.scored_energies = form.scored;
}

ShotSimulator::~ShotSimulator() = default;

void ShotSimulator::check_scene(const Footprint& footprint) const { build_scene(footprint); }

void ShotSimulator::check_vegetation(const Footprint& footprint) const {
  if (!vegetation_) return;
  const Terrain& terrain = scenes_.terrain();
  const FootprintFrame where = footprint_frame(terrain, lidar_, footprint);
  // The half size build_scene gives the region.
  const double half_size_m =
      traced_patch_half_size_m(terrain, lidar_, footprint, where.frame, lidar_.max_angle_rad()) +
      vegetation_margin_m;
  vegetation_->check_region(
      {terrain, where.frame, half_size_m, where.orientation, lidar_.band_count()});
}

void ShotSimulator::share_scenes_along(const Track& track) {
  stretches_.reset();
  if (vegetation_ && !vegetation_->fixed_on_the_ground()) return;
  const double margin_m = vegetation_ ? vegetation_margin_m : 0.0;
  const RoughnessField& roughness = scenes_.roughness();
  if (settings_.stretch_shots > 0) {
    if (!roughness.enabled())
      stretches_ = std::make_unique<StretchScenes>(scenes_, lidar_, track, margin_m,
                                                   settings_.stretch_shots);
    return;
  }
  // A strip meshes its beams' roughness on one lattice, on the terrain's own mesh: a terrain of
  // finer detail than the lattice's, which a shot's own scene meshes more finely under the beam,
  // keeps a scene a shot.
  if (settings_.strip_shots <= 0 ||
      (roughness.enabled() && scenes_.terrain().detail_m() < roughness.spacing_m()))
    return;
  // A track of one shot (a point) has nothing to share: it keeps its own scene.
  if (track.sequence_length() < 2) return;
  // Footprints too far apart for a strip (GLAS's 172 m) build their own scenes from the start,
  // in the run's small batches: its first two footprints tell.
  const Footprint a = track.locate_shot(0), b = track.locate_shot(1);
  if (a.on_terrain && b.on_terrain) {
    const Vec3 step = LocalFrame(a.ground).to_local(b.ground);
    const double half_strip_m =
        std::hypot(step[0], step[1]) * static_cast<double>(settings_.strip_shots / 2);
    if (half_strip_m > max_stretch_reach_m) return;
  }
  stretches_ = std::make_unique<StretchScenes>(scenes_, lidar_, track, margin_m,
                                               settings_.strip_shots, StretchShape::strip);
}

namespace {

// The sun at the footprint, where the shot has a position and a time ERFA can take (or the
// stretch's, interpolated to the shot): ERFA's slow terms interpolated between whole minutes, the
// twentieth of a full evaluation that a few-ray shot could not afford.
void set_sun(ShotRecord& record, const std::optional<StretchSun>& stretch = std::nullopt) {
  if (stretch) {
    const SolarPosition sun = stretch->at(record.shot_number);
    record.solar_elevation_deg = sun.elevation_deg;
    record.solar_azimuth_deg = sun.azimuth_deg;
    return;
  }
  if (!std::isfinite(record.lat_deg) || !std::isfinite(record.lon_deg)) return;
  try {
    const SolarPosition sun =
        solar_position_interpolated(record.time_s, record.lat_deg, record.lon_deg,
                                    std::isfinite(record.elev_m) ? record.elev_m : 0.0);
    record.solar_elevation_deg = sun.elevation_deg;
    record.solar_azimuth_deg = sun.azimuth_deg;
  } catch (const std::invalid_argument&) {
    // A time outside 1900-2100: the sun's place is not known, and stays fill.
  }
}

}  // namespace

ShotRecord ShotSimulator::simulate(const Footprint& footprint, std::int64_t* ray_queries) const {
  ShotRecord record;
  record.shot_number = footprint.shot_number;
  record.source_shot_number = footprint.source_shot_number;
  record.time_s = footprint.time_s;
  record.sc_lat_deg = footprint.spacecraft.lat_deg;
  record.sc_lon_deg = footprint.spacecraft.lon_deg;
  record.sc_alt_m = footprint.spacecraft.h_m;
  record.off_nadir_deg = footprint.off_nadir_deg;
  if (footprint.beam >= 0 && footprint.beam < kNoBeam)
    record.beam = static_cast<std::uint8_t>(footprint.beam);
  record.degrade_flag = footprint.degrade_flag;
  // A stretch knows which of its footprints are on the terrain's data.
  std::shared_ptr<const StretchScene> stretch =
      stretches_ && footprint.on_terrain ? stretches_->find(footprint) : nullptr;
  if (!(stretch && stretch->holds(footprint.shot_number)) &&
      !beam_on_terrain_data(scenes_.terrain(), lidar_, footprint)) {
    flag_off_terrain(record, footprint);
    set_sun(record);
    return record;
  }
  const ShotScene shot = scene_of(footprint, std::move(stretch));
  locate(record, footprint, shot);
  set_sun(record, shot.stretch ? shot.stretch->sun : std::nullopt);
  trace(record, footprint, shot, ray_queries);
  return record;
}

// The shot's returns traced through its scene, received, and the truth and outline beside them.
void ShotSimulator::trace(ShotRecord& record, const Footprint& footprint, const ShotScene& shot,
                          std::int64_t* ray_queries) const {
  const Scene& scene = *shot.built().scene;
  ShotReturns returns;
  returns.waveforms = simulate_shot(scene, lidar_, shot.geometry, shot.built().optics,
                                    settings_.transport, footprint.shot_number);
  if (ray_queries)
    *ray_queries += returns.waveforms.ray_queries + (outline_read() ? outline_vertices : 0);
  scale_pulse_energy(returns.waveforms, footprint.pulse_energy_scale);
  record.atmosphere_transmission = returns.waveforms.atmosphere_transmission;
  record.atmosphere_scattered_fraction = returns.waveforms.atmosphere_scattered_fraction;
  record.atmosphere_delay_m = returns.waveforms.atmosphere_delay_m;
  returns.shot_number = footprint.shot_number;
  returns.beam = footprint.beam;
  returns.range_m = footprint.range_m;
  returns.position_at = [&shot](double time_ns) {
    return shot.on_axis(0.5 * speed_of_light_m_s * time_ns * 1e-9);
  };
  receiver_->receive(std::move(returns), record);
  // The receiver's reflectance divides by the sensor's pulse energy, not the beam's.
  if (footprint.pulse_energy_scale != 1.0)
    for (double& r : record.reflectance) r /= footprint.pulse_energy_scale;
  // The truth over the footprint, beside the estimates: what the beam really fell on.
  const BeamSpot spot{shot.centre_m[0], shot.centre_m[1],
                      footprint.range_m * lidar_.beam_sigma_rad()};
  const auto own_truth = [&] {
    const std::vector<double> nadir = nadir_projection(shot.built().optics);
    return vegetation_ ? vegetation_->truth(scene, spot, nadir)
                       : measure_vegetation(scene, spot, nadir);
  };
  const VegetationTruth truth =
      shot.stretch && shot.stretch->truth ? shot.stretch->truth->measure(spot) : own_truth();
  record.cover_true = truth.cover;
  record.pgap_true = truth.gap_probability;
  record.pai_true = truth.pai;
  record.canopy_height_true_m = truth.canopy_height_m;
  if (outline_read())
    record.footprint_lonlat = beam_outline(scene, lidar_, shot.geometry, shot.frame());
}

// The footprint's place, its ground's orientation and the bins' elevations along the beam axis
// from the footprint centre.
void ShotSimulator::locate(ShotRecord& record, const Footprint& footprint,
                           const ShotScene& shot) const {
  record.lat_deg = footprint.ground.lat_deg;
  record.lon_deg = footprint.ground.lon_deg;
  record.elev_m = footprint.ground.h_m;
  record.range_m = footprint.range_m;
  record.slope_deg = shot.orientation.slope_deg;
  record.aspect_deg = shot.orientation.aspect_deg;
  auto elevation_at = [&](double time_ns) {
    return shot.on_axis(0.5 * speed_of_light_m_s * time_ns * 1e-9).h_m;
  };
  record.elev_bin0_m = elevation_at(lidar_.bin_time_ns(0));
  record.elev_lastbin_m = elevation_at(lidar_.bin_time_ns(lidar_.bins() - 1));
}

std::optional<ShotWaveforms> ShotSimulator::simulate_ray(const Footprint& footprint,
                                                         std::int64_t ray,
                                                         const RayObserver& observer) const {
  if (!beam_on_terrain_data(scenes_.terrain(), lidar_, footprint)) return std::nullopt;
  const ShotScene shot = scene_of(footprint, stretches_ ? stretches_->find(footprint) : nullptr);
  return glaswave::simulate_ray(*shot.built().scene, lidar_, shot.geometry, shot.built().optics,
                                settings_.transport, footprint.shot_number, ray, observer);
}

void ShotSimulator::flag_off_terrain(ShotRecord& record, const Footprint& footprint) const {
  record.quality_flag = quality_invalid;
  // The axis met the terrain, yet nodata or the DEM's edge lies under the beam.
  record.quality_reason = footprint.on_terrain ? reason_nodata : reason_off_terrain;
  const TransportOptions& transport = settings_.transport;
  const std::size_t orders =
      transport.per_order ? static_cast<std::size_t>(transport.max_order) : 0;
  fill_flagged(record, {.bands = lidar_.band_count(),
                        .bins = static_cast<std::size_t>(lidar_.bins()),
                        .orders = orders,
                        .atmosphere = transport.atmosphere.has_value()});
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

ShotSimulator::FootprintScene ShotSimulator::build_scene(const Footprint& footprint) const {
  const Terrain& terrain = scenes_.terrain();
  FootprintScene shot{footprint_frame(terrain, lidar_, footprint), {}};
  const double half_size_m = traced_patch_half_size_m(terrain, lidar_, footprint, shot.where.frame,
                                                      lidar_.max_angle_rad()) +
                             (vegetation_ ? vegetation_margin_m : 0.0);
  // Roughness is subdivided only where the beam is: beyond 4.5 sigma go 4e-5 of the rays.
  const double rough_half_size_m =
      scenes_.roughness().enabled()
          ? traced_patch_half_size_m(
                terrain, lidar_, footprint, shot.where.frame,
                std::min(lidar_.max_angle_rad(), 4.5 * lidar_.beam_sigma_rad()))
          : 0.0;
  shot.built =
      scenes_.build(shot.where.frame, shot.where.orientation, half_size_m, rough_half_size_m);
  return shot;
}

ShotSimulator::ShotScene ShotSimulator::scene_of(
    const Footprint& footprint, std::shared_ptr<const StretchScene> stretch) const {
  ShotScene shot;
  shot.stretch = std::move(stretch);
  if (!shot.stretch) {
    shot.own = build_scene(footprint);
    shot.geometry = shot.own->where.geometry;
    shot.orientation = shot.own->where.orientation;
  } else {
    const LocalFrame& frame = shot.stretch->frame;
    shot.geometry.sensor_m = frame.local_from_ecef(footprint.spacecraft_ecef);
    shot.geometry.axis = frame.local_direction(footprint.beam_ecef);
    shot.geometry.range_m = footprint.range_m;
    shot.centre_m = frame.to_local(footprint.ground);
    // The ground fitted under the shot's own beam, for the record alone: fill when unread.
    if (settings_.shot_fields_read)
      shot.orientation = footprint_frame(scenes_.terrain(), lidar_, footprint).orientation;
    else
      shot.orientation.slope_deg = shot.orientation.aspect_deg =
          std::numeric_limits<double>::quiet_NaN();
  }
  // The atmosphere's layers stand on the ground under the footprint centre (the transport's
  // ShotGeometry).
  shot.geometry.ground_z_m = shot.centre_m[2];
  shot.geometry.ground_height_m = footprint.ground.h_m;
  return shot;
}

}  // namespace glaswave
