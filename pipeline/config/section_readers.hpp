// The section readers parse_config calls, each in the file of its group of sections (beside the
// files declaring their keys: sensor_sections.cpp and sensor_keys.cpp, scene_sections.cpp and
// scene_keys.cpp, product_sections.cpp and product_keys.cpp), and the memory check
// (shot_size.cpp). Each reads its section of `root` through the declaration of its keys and
// writes what it read into the resolved configuration. For pipeline/config/ alone.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "canopy/canopy_settings.hpp"
#include "core/part_kind.hpp"
#include "footprints/receiver_traits.hpp"
#include "pipeline/config/config.hpp"
#include "pipeline/config/json_reader.hpp"

namespace glaswave {

// A per-band optical property: one number for every band, or an object keyed by band name that
// gives every band its own value. Resolved in band order; written to `resolved` as given.
std::vector<double> spectral(JsonReader& reader, const std::string& key,
                             const std::vector<LidarBand>& bands);

SensorSettings read_sensor(JsonReader& root);
// None when the section is absent.
std::optional<AtmosphereSettings> read_atmosphere(JsonReader& root,
                                                  const std::vector<LidarBand>& bands);
// Each band's two-way transmission through the layers' whole vertical column.
void set_band_transmissions(SensorSettings& sensor, const AtmosphereSettings& atmosphere);
DetectorSettings read_detector(JsonReader& root);

SimulationSettings read_simulation(JsonReader& root);
// The terrain, which the caller has seen to be given.
TerrainSettings read_terrain(JsonReader& root, const std::vector<LidarBand>& bands);
// The canopy of `root`'s "canopy" object, its per-band optics in the order of `bands`; none (bare
// ground) when the key is absent or null. The stands file reads its features' canopy keys with
// it too, as overrides of the scene's.
std::optional<CanopySettings> read_canopy(JsonReader& root, const std::vector<LidarBand>& bands);
TrackSettings read_track(JsonReader& root, const SensorSettings& sensor);

// output.geojson, the old name of output.footprints, read with a warning into `warnings`.
OutputSettings read_output(JsonReader& root, std::vector<std::string>& warnings);
BrfSettings read_brf(JsonReader& root);
TableSettings read_table(JsonReader& root);

// What the sensor's receiver declared it is (core/part_kind.hpp), which the rules across keys ask
// instead of its name; none of its traits for a name no receiver declared (its key refuses it).
inline ReceiverTraits receiver_traits_of(const SensorSettings& sensor) {
  return declared_traits<ReceiverTraits>(sensor.receiver).value_or(ReceiverTraits{});
}

// The names of the receivers whose traits satisfy `keep`, as a message lists them.
template <typename Keep>
std::string receivers_that(Keep keep) {
  return quoted_alternatives(declared_kinds<ReceiverTraits>(keep));
}

// Refuses a shot whose waveforms would take more than run_limits::shot_waveform_bytes, at the
// key that makes them large.
void check_shot_size(const Config& c);

}  // namespace glaswave
