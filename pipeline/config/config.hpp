// The configuration of a run, parsed once from JSON into typed settings with defaults and
// ranges checked. Every error names its JSON path; the transport never sees JSON.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "canopy/canopy_settings.hpp"
#include "core/error.hpp"
#include "core/part_switch.hpp"
#include "footprints/atmosphere_settings.hpp"
#include "footprints/lidar_settings.hpp"
#include "footprints/track_settings.hpp"
#include "pipeline/config/json_text.hpp"  // read_json_file and apply_override, as load_config
#include "terrain/terrain_settings.hpp"

namespace glaswave {

// The sensor: the lidar the transport and the receivers use (the seed's Table 2, with the
// `north2010` preset's defaults), the photon-counting detector, and what the configuration says
// beside them.
struct SensorSettings : LidarSettings, PhotonDetectorSettings {
  std::string preset;           // "north2010", "glas", "gedi", "atlas" or empty
  double pulse_rate_hz = 40.0;  // the laser's: a track's shot rate when it gives none
  // What makes the record: "waveform" (the received waveform and its processing) or
  // "photon_counting" (ICESat-2's photon events; docs/icesat2.md), with the photon-counting
  // receiver's detector (PhotonDetectorSettings, ATLAS's by default) and its beams.
  std::string receiver = "waveform";
  std::vector<std::string> beams = {"gt2l"};
  // The spacecraft's yaw, "backward" or "forward" (footprints/atlas_beams.hpp): which beam of
  // each pair is strong and each ground track's ATLAS spot.
  std::string sc_orient = "backward";
};

struct SimulationSettings {
  std::int64_t rays_per_shot = 10000;
  int max_order = 8;
  bool quasi_random = false;  // "sampling": "sobol" (true) or "random"
  // Photon counting's background light: "sun" (the sun at each shot's time and place over the
  // scene's reflectance), "none", or "rate" (background_rate_MHz).
  std::string background = "sun";
  double background_rate_MHz = 0.0;
};

// RAMI-IV's lidar measurements written by `glaswave run` in ROMC's format (docs/guide/rami.md):
// `DIR/rami/<measurement>_<model>-<experiment>.mes`, the return binned by height from the ground
// up, one experiment a band.
struct RamiLidarSettings {
  std::vector<std::string> measurements = {"lidar_sgl_co", "lidar_tot"};
  std::string experiment;          // ROMC's identifier; "{band}" is replaced by the band's name
  std::string model = "glaswave";  // ROMC's model identifier: up to 10 letters and digits
  double height_bin_m = 0.5;       // RAMI's height interval: a whole number of window bins
};

struct OutputSettings {
  bool netcdf = true;
  bool footprints = true;  // the footprints' layer, in footprints_format
  bool plots = false;
  bool per_order = false;
  bool metrics = true;                        // the waveform metrics and Gaussian decomposition
  std::string footprints_format = "GeoJSON";  // "GeoJSON" or "GPKG"
  std::string glas_ellipsoid = "wgs84";       // "wgs84" or "topex": the GLAS granules' heights
  // The ICESat-2 granules (atl03.h5, atl08.h5); absent: on with the photon-counting receiver.
  std::optional<bool> atl03, atl08;
  // The switches product writers declare in their own files (core/part_switch.hpp): the GEDI
  // granules' gedi_l1b and gedi_l2a, the GLAS granules' glah01 and glah14, and a new writer's.
  PartSwitches switches;
  std::optional<RamiLidarSettings> rami;  // RAMI-IV's lidar measurements; absent: none
};

struct BrfView {
  double zenith_deg = 0.0;
  double azimuth_deg = 0.0;
};

// RAMI's measurement set written by `glaswave brf` in ROMC's format (PRODUCT.md section 13):
// `DIR/rami/<measurement>_<model>-<experiment>.mes`, one experiment a band.
struct BrfRamiSettings {
  std::vector<std::string> measurements = {"brfpp", "brfop", "fabs", "ftran", "falb"};
  // ROMC's experiment identifier; "{band}" is replaced by each band's name (needed with more
  // than one band, since an experiment is one band's).
  std::string experiment;
  std::string model = "glaswave";  // ROMC's model identifier: up to 10 letters and digits
};

// Settings of `glaswave brf` (FLIGHT's solar mode).
struct BrfSettings {
  double sun_zenith_deg = 30.0;
  double sun_azimuth_deg = 0.0;
  std::vector<BrfView> views = {BrfView{}};
  std::int64_t photons = 1000000;
  double image_resolution_m = 1.0;
  double scene_size_m = 300.0;  // tile side: 100 m (one draw of ~50 crowns) was 4.7 % off
  std::optional<BrfRamiSettings> rami;

  // The tile's side in whole pixels (scene_size_m rounded up), as scene.tif and the traced tile
  // have it, and its half-size in m.
  double pixels() const { return std::ceil(scene_size_m / image_resolution_m); }
  double tile_half_size_m() const { return 0.5 * pixels() * image_resolution_m; }
};

// Settings of `glaswave table` (PRODUCT.md section 11): the forward table the `rt` retrieval
// searches. Each entry is the configuration with the varied keys set as `--set` would set them.
struct TableSettings {
  // Keys (dotted paths, as --set names them) sampled over [low, high] by a seeded
  // low-discrepancy design, in the order given.
  std::vector<std::pair<std::string, std::array<double, 2>>> vary;
  // Keys and the values they take (each read as --set reads VALUE: JSON when it parses, else a
  // string), chosen by the design's coordinate of their own.
  std::vector<std::pair<std::string, std::vector<std::string>>> values;
  std::int64_t entries = 1000;
  // The track's first shots simulated for each entry: their mean is the entry's waveform and
  // their scatter the table's Monte Carlo noise.
  std::int64_t shots_per_entry = 2;
};

// The sensor preset that gives the sensor's defaults.
inline constexpr const char* default_sensor_preset = "north2010";

// Sizes beyond which a run cannot be physical or would not fit in memory; the configuration
// refuses them, naming the limit.
namespace run_limits {
inline constexpr std::uint64_t bands = 256;               // the detector keys its noise by band
inline constexpr std::uint64_t waveform_bins = 1u << 24;  // ... and by bin
// A core traces about 1e5 rays a second through a forest: 1e9 rays is hours for one shot, and
// its Monte Carlo error (3e-5) is far below any use.
inline constexpr std::uint64_t rays_per_shot = 1'000'000'000;
inline constexpr std::uint64_t max_order = 1000;  // a ray's weight is gone long before
// Spaceborne and airborne lidars see a few milliradians at most; the scene under the field of
// view grows with the angle (and with the range).
inline constexpr double angle_rad = 0.05;
// The highest spacecraft: above geostationary height (35786 km) nothing points a lidar down.
inline constexpr double altitude_m = 4.0e7;
inline constexpr std::uint64_t track_shots = 1'000'000'000;  // 290 days of GLAS at 40 Hz
// What one shot's waveforms may take: the transport tallies each shot's rays in 65 copies of
// them (transport_waveform_copies) and every thread simulates a shot.
inline constexpr double shot_waveform_bytes = 4.0 * 1024 * 1024;
// `glaswave brf`'s tile is flat and periodic in the first footprint's local frame: 10 km across,
// its corners (7.1 km out) already lie 3.9 m below that plane on the curved Earth.
inline constexpr double brf_scene_m = 10000.0;
inline constexpr double brf_image_pixels = 8192;  // scene.tif's side (2^26 pixels a band)
// The copies of scene.tif's bands `brf` holds: the tallied image and the one written.
inline constexpr double brf_image_copies = 2.0;
}  // namespace run_limits

struct Config {
  std::uint64_t seed = 1;
  SensorSettings sensor;
  // The layers the light crosses (`"atmosphere"`, presets expanded for the bands); empty: none,
  // and each band's fixed atmos_transmission_roundtrip.
  std::optional<AtmosphereSettings> atmosphere;
  SimulationSettings simulation;
  TerrainSettings terrain;
  std::optional<CanopySettings> canopy;  // empty: bare ground
  TrackSettings track;
  OutputSettings output;
  DetectorSettings detector;
  BrfSettings brf;
  TableSettings table;
  // The configuration as used, presets expanded and defaults filled in; written into products.
  nlohmann::json resolved;
  // What the user should know about the configuration itself (an old key's name), one line each.
  std::vector<std::string> warnings;
};

// Calls `open`, which builds a floor below the configuration from the settings of `section` (a
// JSON pointer such as "/terrain"), and turns an error that names one of those settings into one
// at its JSON path: the floors below never see JSON.
template <typename Open>
auto at_section(const std::string& section, Open&& open) -> decltype(open()) {
  try {
    return open();
  } catch (const Error& e) {
    if (e.names_setting()) throw e.in_section(section);
    throw;
  }
}

// Turns a configuration document into settings: presets expanded, defaults filled in, every
// value checked. Unknown keys are errors that suggest the nearest known key.
Config parse_config(const nlohmann::json& document);

// What `run` needs of its outputs beyond a configuration that simulates: something to write,
// both products for the plots, a footprints format the writers have. `check_run` (the engine's,
// with the memory a run will hold) asks it, and `check` with it, so that the two accept exactly
// the same configurations.
void check_outputs(const Config& config);

// The bytes of one shot's waveforms: bands x tally bins (the window and the pulse's margin on
// each side, as pipeline/transport/lidar_model.hpp sizes them) x waveforms (total, canopy,
// ground, and one per order) x 8. Computed in double, so that no size overflows on the way.
// parse_config refuses a shot beyond run_limits::shot_waveform_bytes; the engine's memory
// estimate counts it for every thread.
struct ShotSize {
  double bands, window_bins, margin_bins, waveforms, bytes;
};
ShotSize shot_size(const Config& config);

// A size for an error message, in MiB to one decimal ("13.7 MiB").
std::string mebibytes(double bytes);

// read_json_file + apply_override for each + parse_config.
Config load_config(const std::filesystem::path& file, const std::vector<std::string>& overrides);

// The same for a configuration that comes as a document rather than a file (a dict in Python):
// relative paths in it are taken from `folder`, as load_config takes them from the file's.
Config load_config_document(nlohmann::json document, const std::filesystem::path& folder,
                            const std::vector<std::string>& overrides);

}  // namespace glaswave
