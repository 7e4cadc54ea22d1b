// Opening the run's inputs, with errors at their JSON paths.
#include "pipeline/engine/inputs.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>

#include "canopy/cloud_terrain.hpp"
#include "footprints/atlas_beams.hpp"

namespace glaswave {

std::unique_ptr<Terrain> open_terrain(const Config& config) {
  if (config.terrain.point_cloud)  // the parser saw that canopy.point_cloud is given
    return at_section("/canopy/point_cloud",
                      [&] { return point_cloud_terrain(config.terrain, *config.canopy); });
  return at_section("/terrain", [&] { return make_terrain(config.terrain); });
}

ShotSettings shot_settings(const Config& config) {
  ShotSettings settings;
  settings.lidar = config.sensor;  // the sensor's lidar, as the configuration read it
  settings.transport.rays = config.simulation.rays_per_shot;
  settings.transport.max_order = config.simulation.max_order;
  settings.transport.quasi_random = config.simulation.quasi_random;
  // A receiver may need every order (photon counting gives each photon its own).
  const ReceiverTraits receiver =
      at_section("/sensor", [&] { return receiver_traits(config.sensor.receiver); });
  settings.transport.per_order = config.output.per_order || receiver.every_order;
  settings.transport.seed = config.seed;
  settings.transport.atmosphere = config.atmosphere;
  settings.soil_reflectance = config.terrain.soil_reflectance;
  settings.roughness = config.terrain.roughness;
  // Photon counting's 10 kHz footprints overlap almost entirely: they share their stretch's scene.
  if (receiver.shares_scenes) settings.stretch_shots = stretch_shots;
  // Waveform footprints close along their beam (GEDI's 60 m apart) share a strip's scene, on any
  // track: a pass, an orbit, an ephemeris, a granule's beams, points in order.
  else
    settings.strip_shots = strip_shots;
  return settings;
}

// The photon-counting receiver's settings: the configuration's, one for each of its beams.
std::vector<PhotonCountingSettings> photon_settings(const Config& config) {
  std::vector<PhotonCountingSettings> beams;
  for (const AtlasBeam& beam :
       select_atlas_beams(config.sensor.beams, atlas_orientation(config.sensor.sc_orient))) {
    PhotonCountingSettings p;
    static_cast<PhotonDetectorSettings&>(p) = config.sensor;  // the sensor's detector, whole
    p.channels = beam.strong ? 16 : 4;
    p.energy_ratio = beam.energy_ratio;
    p.beam = static_cast<std::uint32_t>(beam.spot_number);
    p.background = config.simulation.background == "sun"    ? BackgroundSource::sun
                   : config.simulation.background == "none" ? BackgroundSource::none
                                                            : BackgroundSource::rate;
    p.background_rate_Hz = config.simulation.background_rate_MHz * 1e6;
    p.keep_orders = config.output.per_order;
    beams.push_back(p);
  }
  return beams;
}

ReceiverSettings receiver_settings(const Config& config) {
  ReceiverSettings settings;
  settings.kind = config.sensor.receiver;
  if (at_section("/sensor", [&] { return receiver_traits(settings.kind); }).atlas_beams)
    settings.photons = photon_settings(config);
  settings.lidar = config.sensor;
  settings.metrics = config.output.metrics;
  settings.seed = config.seed;
  if (config.detector.enabled) settings.detector = config.detector;
  settings.atmosphere = config.atmosphere;  // the sun's background through the layers
  return settings;
}

VegetationSettings vegetation_settings(const Config& config) {
  return {*config.canopy, config.seed, config.terrain.plane, nullptr};
}

std::unique_ptr<VegetationSource> grow_vegetation(const Config& config, const Terrain* terrain) {
  if (!config.canopy) return nullptr;
  VegetationSettings settings = vegetation_settings(config);
  if (terrain) settings.cloud_ground = cloud_ground_of(*terrain);  // gridded once, not twice
  return at_section("/canopy", [&] { return make_vegetation_source(settings); });
}

namespace {

std::unique_ptr<ShotSimulator> make_simulator(const Config& config, const Terrain& terrain,
                                              bool shot_fields_read, bool outline_read) {
  std::unique_ptr<VegetationSource> vegetation = grow_vegetation(config, &terrain);
  ReceiverSettings receiver = receiver_settings(config);
  receiver.metrics_read = shot_fields_read;
  std::unique_ptr<Receiver> made = at_section("/detector", [&] { return make_receiver(receiver); });
  ShotSettings shot = shot_settings(config);
  shot.shot_fields_read = shot_fields_read;
  shot.outline_read = outline_read;
  return std::make_unique<ShotSimulator>(shot, terrain, std::move(vegetation), std::move(made));
}

}  // namespace

std::unique_ptr<ShotSimulator> make_shot_simulator(const Config& config, const Terrain& terrain) {
  return make_simulator(config, terrain, true, true);
}

bool products_read_shot_fields(const OutputSettings& output) {
  // A writer that declares its own switch is taken to read them (the GEDI granules do).
  bool switched = false;
  for (const auto& [name, on] : output.switches) switched = switched || on;
  return output.netcdf || output.footprints || switched;
}

std::unique_ptr<ShotSimulator> make_run_shot_simulator(const Config& config,
                                                       const Terrain& terrain) {
  // The beam's outline is the footprint polygons' alone (footprints.geojson or .gpkg).
  return make_simulator(config, terrain, products_read_shot_fields(config.output),
                        config.output.footprints);
}

RunInfo run_info(const Config& config, const ShotSimulator& simulator, std::int64_t shots,
                 const std::string& command_line) {
  const LidarModel& lidar = simulator.lidar();
  RunInfo info;
  info.command_line = command_line;
  try {
    info.created = product_creation_time();
  } catch (const std::invalid_argument& e) {
    throw config_error("SOURCE_DATE_EPOCH", e.what());
  }
  info.config_json = config.resolved.dump();
  info.seed = config.seed;
  info.shots = shots;
  for (const LidarBand& band : config.sensor.bands)
    info.bands.push_back({band.name, band.wavelength_nm, band.atmos_transmission_roundtrip});
  info.bin_time_ns = lidar.bin_time_ns();
  info.tx_time_ns = lidar.tx_time_ns();
  for (std::size_t band = 0; band < lidar.band_count(); ++band)
    info.tx_waveform_W.push_back(lidar.tx_waveform_W(band));
  info.orders = config.output.per_order ? config.simulation.max_order : 0;
  info.photon_events = simulator.receiver().photon_events();
  info.atmosphere = config.atmosphere.has_value();
  const DetectorSettings& d = config.detector;
  if (d.enabled) info.detector_gain = d.gain;
  if (d.enabled && d.bits > 0 && d.saturation_W && *d.saturation_W > 0) {
    info.counts_per_W = d.gain * (std::ldexp(1.0, d.bits) - 1.0) / *d.saturation_W;
    info.full_scale_counts = std::ldexp(1.0, d.bits) - 1.0;
  }
  return info;
}

namespace {

// GLAH01's and GLAH14's i_rec_ndx is a 4-byte integer (the GLAH dictionary's): a shot number
// past 40 x (2^31 - 1) + 39 has no record index the granule can hold.
void check_glas_record_index(const Config& config, const Track& track) {
  const bool glah01 = switched_on(config.output.switches, "glah01");
  const bool glah14 = switched_on(config.output.switches, "glah14");
  if (!glah01 && !glah14) return;
  constexpr std::int64_t most = std::int64_t{std::numeric_limits<std::int32_t>::max()} * 40 + 39;
  const std::int64_t largest = track.largest_source_shot_number();
  if (largest <= most) return;
  throw config_error(glah14 ? "/output/glah14" : "/output/glah01",
                     "the track's shot numbers reach " + std::to_string(largest) +
                         " (a GEDI granule's), and a GLAS granule numbers a shot by its 1 s "
                         "record, i_rec_ndx, a 4-byte integer up to 2147483647 (shot numbers to " +
                         std::to_string(most) +
                         "): every shot would have the same record; write GEDI products "
                         "(output.gedi_l1b, gedi_l2a) for this track");
}

}  // namespace

std::unique_ptr<Track> plan_track(const Config& config, const Terrain& terrain) {
  if (!at_section("/sensor", [&] { return receiver_traits(config.sensor.receiver); }).atlas_beams) {
    auto track =
        at_section("/track", [&] { return std::make_unique<Track>(config.track, terrain); });
    check_glas_record_index(config, *track);
    return track;
  }
  // A photon-counting pass: each beam flies its own ground track about the reference one, its
  // footprints carrying its spot number, the receiver's key for it.
  const std::vector<AtlasBeam> beams =
      select_atlas_beams(config.sensor.beams, atlas_orientation(config.sensor.sc_orient));
  if (config.track.type != TrackType::pass) {
    if (beams.size() > 1)
      throw config_error("/sensor/beams",
                         "several beams fly a pass only (track.type \"pass\"); other tracks "
                         "give one beam's footprints: name one beam");
    return at_section("/track", [&] { return std::make_unique<Track>(config.track, terrain); });
  }
  std::vector<BeamPass> passes;
  for (const AtlasBeam& beam : beams)
    passes.push_back({beam_pass(config.track, beam), beam.spot_number});
  return at_section("/track", [&] { return std::make_unique<Track>(passes, terrain); });
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

std::optional<std::string> crowns_off_track(const Config& config,
                                            const VegetationSource* vegetation,
                                            const std::vector<std::array<double, 2>>& shots) {
  if (!vegetation || shots.empty() || !config.canopy) return std::nullopt;
  const std::vector<VegetationSource::Placed> trees = vegetation->placed();
  if (trees.empty()) return std::nullopt;
  double lat_min = 90.0, lat_max = -90.0, lon_min = 360.0, lon_max = -360.0, radius_m = 0.0;
  for (const auto& tree : trees) {
    lat_min = std::min(lat_min, tree.lat_deg), lat_max = std::max(lat_max, tree.lat_deg);
    lon_min = std::min(lon_min, tree.lon_deg), lon_max = std::max(lon_max, tree.lon_deg);
    radius_m = std::max(radius_m, tree.radius_m);
  }
  constexpr double margin_m = 100.0;              // a beam and its diffuse light, as for stands
  constexpr double metres_per_degree = 111320.0;  // ample for a distance of warning
  double nearest_m = std::numeric_limits<double>::infinity();
  for (const auto& [lat, lon] : shots) {
    if (!std::isfinite(lat) || !std::isfinite(lon)) continue;
    const double east = std::cos(lat * std::numbers::pi / 180.0) * metres_per_degree;
    const double dlat = std::max({lat_min - lat, 0.0, lat - lat_max}) * metres_per_degree;
    // Longitudes compared on the shorter way round.
    double dlon = std::numeric_limits<double>::infinity();
    for (const double turn : {-360.0, 0.0, 360.0})
      dlon = std::min(dlon, std::max({lon_min - (lon + turn), 0.0, lon + turn - lon_max}));
    nearest_m = std::min(nearest_m, std::hypot(dlat, dlon * east) - radius_m);
  }
  if (!(nearest_m > margin_m)) return std::nullopt;
  char distance[32];
  std::snprintf(distance, sizeof distance, "%.3g km", nearest_m / 1000.0);
  const std::string within = " within " + std::to_string(static_cast<int>(margin_m)) +
                             " m of any of the " + std::to_string(shots.size()) +
                             " footprints (the nearest is " + distance + " away); ";
  // Each source's key and words: the warning names the file the user gave.
  const CanopySettings& c = *config.canopy;
  if (!c.facet_trees_file.empty())
    return "/canopy/facets/trees_file: none of the " + std::to_string(trees.size()) + " trees of " +
           c.facet_trees_file + " lies" + within +
           "check its coordinates (lon,lat in degrees, x,y in metres from terrain.plane's origin, "
           "or its layer's CRS)";
  if (!c.voxels_file.empty() || !c.point_cloud_file.empty()) {
    const bool grid = !c.voxels_file.empty();
    return std::string(grid ? "/canopy/voxels/file: the grid of " : "/canopy/point_cloud/file: ") +
           (grid ? c.voxels_file : "the cloud " + c.point_cloud_file) + " lies nowhere" + within +
           "the shots see bare ground; check its CRS and where the track runs";
  }
  return "/canopy/crowns_file: none of the " + std::to_string(trees.size()) + " crowns of " +
         c.crowns_file + " lies" + within +
         "check its coordinates (lon,lat in degrees, or x,y in metres from terrain.plane's "
         "origin)";
}

}  // namespace glaswave
