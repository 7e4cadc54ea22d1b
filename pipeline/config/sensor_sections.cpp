// The readers of the lidar's sections and the air it looks through (their keys: sensor_keys.cpp):
// `sensor` with its preset and bands, `atmosphere`, `detector`; and the per-band values every
// section reads in the sensor's band order.
#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "core/names.hpp"
#include "pipeline/config/atmosphere_presets.hpp"
#include "pipeline/config/json_reader.hpp"
#include "pipeline/config/json_text.hpp"
#include "pipeline/config/keys.hpp"
#include "pipeline/config/presets.hpp"
#include "pipeline/config/section_readers.hpp"

namespace glaswave {

using nlohmann::json;

namespace {

// ---- spectral properties --------------------------------------------------------------------

std::string band_list(const std::vector<LidarBand>& bands) {
  std::string list;
  for (std::size_t i = 0; i < bands.size(); ++i) list += (i ? ", " : "") + bands[i].name;
  return list;
}

}  // namespace

// A per-band optical property: one number for every band, or an object keyed by band name that
// gives every band its own value. Resolved in band order; written to `resolved` as given.
std::vector<double> spectral(JsonReader& reader, const std::string& key,
                             const std::vector<LidarBand>& bands) {
  const Key& declared = reader.declared(key, KeyType::spectral);
  if (declared.required) reader.require(key);
  const double fallback = declared.required ? 0.0 : declared.default_value.get<double>();
  const Range& range = declared.range;
  const json& value = reader.raw(key);
  const std::string place = reader.place(key);
  if (value.is_null()) {
    reader.resolved()[key] = fallback;
    return std::vector<double>(bands.size(), fallback);
  }
  if (value.is_number()) {
    const double x = read_number(place, value, range);
    reader.resolved()[key] = value;
    return std::vector<double>(bands.size(), x);
  }
  if (!value.is_object()) {
    throw config_error(place, "must be a number or an object keyed by band name (" +
                                  band_list(bands) + "), got " + describe(value));
  }
  for (const auto& [name, v] : value.items()) {
    bool known = false;
    for (const LidarBand& band : bands) known = known || band.name == name;
    if (!known) {
      throw config_error(json_pointer_child(place, name),
                         "unknown band \"" + name + "\"; the bands are " + band_list(bands));
    }
  }
  std::vector<double> values;
  for (const LidarBand& band : bands) {
    const auto it = value.find(band.name);
    if (it == value.end()) {
      throw config_error(place, "missing band \"" + band.name +
                                    "\": give a value for every band, or one number for all");
    }
    values.push_back(read_number(json_pointer_child(place, band.name), *it, range));
  }
  reader.resolved()[key] = value;
  return values;
}

namespace {

// The preset a sensor section names (the default when it names none), one of the presets there
// are.
std::string sensor_preset(const json& given) {
  if (!given.is_object() || !given.contains("preset") || given["preset"].is_null())
    return default_sensor_preset;
  const json& name = given["preset"];
  if (!name.is_string())
    throw config_error("/sensor/preset", "must be a string, got " + describe(name));
  const std::string preset = name.get<std::string>();
  if (sensor_presets().count(preset)) return preset;
  std::vector<std::string> names;
  std::string known;
  for (const auto& [preset_name, text] : sensor_presets()) {
    names.push_back(preset_name);
    known += (known.empty() ? "" : ", ") + preset_name;
  }
  const std::string suggestion = did_you_mean(preset, names);
  throw config_error("/sensor/preset",
                     "unknown preset \"" + preset + "\"" +
                         (suggestion.empty() ? "; the presets are " + known : suggestion));
}

// The laser's bands, their names unique. With an atmosphere the layers give each band's two-way
// transmission (parse_config sets it): the user's bands may not give it, and a preset's is left
// out of the resolved configuration, which then reads back the same.
void read_bands(JsonReader& r, SensorSettings& s, bool atmosphere, bool bands_given) {
  for (JsonReader& b : r.object_array("bands", true)) {
    LidarBand band;
    for (const char* key : {"name", "wavelength_nm", "pulse_energy_mJ"}) b.require(key);
    if (!atmosphere) b.require("atmos_transmission_roundtrip");
    band.name = b.string("name", "");
    if (band.name.empty()) b.fail("name", "must not be empty");
    for (const LidarBand& other : s.bands)
      if (other.name == band.name) b.fail("name", "duplicate band name \"" + band.name + "\"");
    band.wavelength_nm = b.number("wavelength_nm");
    band.pulse_energy_mJ = b.number("pulse_energy_mJ");
    if (!atmosphere)
      band.atmos_transmission_roundtrip = *b.optional_number("atmos_transmission_roundtrip");
    else if (b.has("atmos_transmission_roundtrip") && bands_given)
      b.fail("atmos_transmission_roundtrip",
             "cannot be given beside \"atmosphere\": the layers give each band's two-way "
             "transmission");
    b.finish();
    s.bands.push_back(band);
  }
}

// The beams of a receiver that flies ATLAS's (ReceiverTraits::atlas_beams).
void check_beams(JsonReader& r, SensorSettings& s) {
  // Given empty, it asks for no beam: gt2l in its place would run without a word.
  if (s.beams.empty() && r.has("beams"))
    r.fail("beams",
           "names no beam: name one or more of gt1l gt1r gt2l gt2r gt3l gt3r, or leave it out "
           "for gt2l");
  r.resolved()["beams"] = s.beams;
  if (!receiver_traits_of(s).atlas_beams) return;
  static const std::vector<std::string> known = {"gt1l", "gt1r", "gt2l", "gt2r", "gt3l", "gt3r"};
  for (const std::string& beam : s.beams)
    if (std::find(known.begin(), known.end(), beam) == known.end())
      r.fail("beams", "no beam \"" + beam + "\"; the beams are gt1l gt1r gt2l gt2r gt3l gt3r" +
                          did_you_mean(beam, known));
  for (auto beam = s.beams.begin(); beam != s.beams.end(); ++beam)
    if (std::find(s.beams.begin(), beam, *beam) != beam)
      r.fail("beams", "names \"" + *beam + "\" twice: its shots would be simulated twice");
}

}  // namespace

SensorSettings read_sensor(JsonReader& root) {
  const json& given = root.raw("sensor");
  if (!given.is_null() && !given.is_object())
    root.fail("sensor", "must be an object, got " + describe(given));

  SensorSettings s;
  // A preset is the base; keys given beside it replace the preset's ("bands" as a whole).
  const std::string preset = sensor_preset(given);
  const auto preset_text = sensor_presets().find(preset);
  json merged =
      preset_text != sensor_presets().end() ? json::parse(preset_text->second) : json::object();
  if (given.is_object())
    for (const auto& [key, value] : given.items()) merged[key] = value;

  const bool atmosphere = !root.raw("atmosphere").is_null();
  const bool bands_given = given.is_object() && given.contains("bands");
  JsonReader r(merged, "/sensor", root.resolved()["sensor"],
               root.declared("sensor", KeyType::object));
  read_fields(r,
              {{"bands", [&] { read_bands(r, s, atmosphere, bands_given); }},
               {"beams", [&] { check_beams(r, s); }}},
              s);
  r.finish();
  return s;
}

namespace {

// ---- the atmosphere -------------------------------------------------------------------------

// A fixed array of numbers, each within its declared range.
std::vector<double> number_tuple(JsonReader& r, const std::string& key) {
  const Key& k = r.declared(key, KeyType::number_tuple);
  const json& value = r.raw(key);
  std::string names;
  for (const auto& [name, range] : k.items) names += (names.empty() ? "" : ", ") + name;
  if (!value.is_array() || value.size() != k.items.size())
    r.fail(key, "must be an array of " + std::to_string(k.items.size()) + " numbers [" + names +
                    "], got " + describe(value));
  std::vector<double> numbers;
  for (std::size_t i = 0; i < k.items.size(); ++i)
    numbers.push_back(
        read_number(r.place(key) + "/" + std::to_string(i), value[i], k.items[i].second));
  r.resolved()[key] = value;
  return numbers;
}

// A layer's phase function: "rayleigh", {"hg_g": g} or {"hg2": [g1, g2, w]}.
AtmospherePhase read_phase(JsonReader& r) {
  const json& value = r.raw("phase");
  AtmospherePhase phase;
  if (value.is_null()) r.fail("phase", "is required");
  if (value == "rayleigh") {
    r.resolved()["phase"] = value;
    return phase;
  }
  if (!value.is_object())
    r.fail("phase",
           "must be \"rayleigh\", {\"hg_g\": g} or {\"hg2\": [g1, g2, w]}, got " + describe(value));
  JsonReader p(value, r.place("phase"), r.resolved()["phase"],
               r.declared("phase", KeyType::choice_or_object));
  const bool hg = p.has("hg_g"), hg2 = p.has("hg2");
  p.finish();
  if (hg == hg2) throw config_error(p.path(), "give exactly one of \"hg_g\" and \"hg2\"");
  if (hg) {
    phase.kind = AtmospherePhase::Kind::henyey_greenstein;
    phase.g1 = *p.optional_number("hg_g");
  } else {
    const std::vector<double> terms = number_tuple(p, "hg2");
    phase.kind = AtmospherePhase::Kind::two_term_henyey_greenstein;
    phase.g1 = terms[0];
    phase.g2 = terms[1];
    phase.weight = terms[2];
  }
  return phase;
}

AtmosphereLayer read_layer(JsonReader& r, const std::vector<LidarBand>& bands) {
  AtmosphereLayer layer;
  const auto check_top = [&] {
    if (!(layer.top_m > layer.base_m))
      r.fail("top_m", "must be above base_m (" + format_number(layer.base_m) + "), got " +
                          format_number(layer.top_m));
  };
  read_fields(
      r,
      {{"top_m", check_top},
       {"optical_depth", [&] { layer.optical_depth = spectral(r, "optical_depth", bands); }},
       {"single_scattering_albedo",
        [&] { layer.single_scattering_albedo = spectral(r, "single_scattering_albedo", bands); }},
       {"phase", [&] { layer.phase = read_phase(r); }}},
      layer);
  r.finish();
  return layer;
}

// A preset's layer as the resolved configuration writes it: per-band values keyed by band name.
json layer_json(const AtmosphereLayer& layer, const std::vector<LidarBand>& bands) {
  json depth = json::object(), albedo = json::object();
  for (std::size_t b = 0; b < bands.size(); ++b) {
    depth[bands[b].name] = layer.optical_depth[b];
    albedo[bands[b].name] = layer.single_scattering_albedo[b];
  }
  json phase = "rayleigh";
  if (layer.phase.kind == AtmospherePhase::Kind::henyey_greenstein)
    phase = {{"hg_g", layer.phase.g1}};
  if (layer.phase.kind == AtmospherePhase::Kind::two_term_henyey_greenstein)
    phase = {{"hg2", {layer.phase.g1, layer.phase.g2, layer.phase.weight}}};
  return {{"base_m", layer.base_m},
          {"top_m", layer.top_m},
          {"above", layer.above_ellipsoid ? "ellipsoid" : "ground"},
          {"optical_depth", depth},
          {"single_scattering_albedo", albedo},
          {"phase", phase}};
}

}  // namespace

// `"atmosphere"`: a preset's name, or {"preset", "layers"} (layers given replace the preset's).
// Absent: nothing, and nothing is written into the resolved configuration, which goes into the
// products as before.
std::optional<AtmosphereSettings> read_atmosphere(JsonReader& root,
                                                  const std::vector<LidarBand>& bands) {
  const json& value = root.raw("atmosphere");
  if (value.is_null()) return std::nullopt;
  const Key& declared = root.declared("atmosphere", KeyType::choice_or_object);
  AtmosphereSettings a;
  json& resolved = root.resolved()["atmosphere"];
  resolved = json::object();
  if (value.is_string()) {
    a.preset = value.get<std::string>();
    if (std::find(declared.choices.begin(), declared.choices.end(), a.preset) ==
        declared.choices.end())
      root.throw_not_one_of("atmosphere", a.preset, declared.choices);
  } else if (value.is_object()) {
    JsonReader r(value, root.place("atmosphere"), resolved, declared);
    a.preset = r.optional_string("preset").value_or("");
    if (!a.preset.empty() && std::find(declared.choices.begin(), declared.choices.end(),
                                       a.preset) == declared.choices.end())
      r.throw_not_one_of("preset", a.preset, declared.choices);
    for (JsonReader& layer : r.object_array("layers", a.preset.empty()))
      a.layers.push_back(read_layer(layer, bands));
    r.finish();
  } else {
    root.fail("atmosphere",
              "must be a preset's name or an object of \"preset\" and \"layers\", got " +
                  describe(value));
  }
  if (!a.preset.empty()) resolved["preset"] = a.preset;
  if (a.layers.empty()) {
    a.layers = atmosphere_preset(a.preset, bands);
    json& layers = resolved["layers"];
    layers = json::array();
    for (const AtmosphereLayer& layer : a.layers) layers.push_back(layer_json(layer, bands));
  }
  return a;
}

// Each band's two-way transmission through the layers' whole vertical column, as the bands'
// fixed value stands for it without an atmosphere (the photon-counting receiver's background,
// the GLAS granules' reflectivity).
void set_band_transmissions(SensorSettings& sensor, const AtmosphereSettings& atmosphere) {
  for (std::size_t b = 0; b < sensor.bands.size(); ++b) {
    double tau = 0.0;
    for (const AtmosphereLayer& layer : atmosphere.layers) tau += layer.optical_depth[b];
    sensor.bands[b].atmos_transmission_roundtrip = std::exp(-2.0 * tau);
  }
}

// `"detector"`: the signal chain from received light to the recorded waveform, in its order:
// background light added, photon statistics, detector noise, gain, saturation, digitiser.
// Off unless "enabled" is true; every level is in W at the detector's input except
// saturation_W, the digitiser's full scale after the gain.
DetectorSettings read_detector(JsonReader& root) {
  DetectorSettings d;
  JsonReader r = root.object("detector");
  const auto check_saturation = [&] {
    if (!d.saturation_W) r.resolved()["saturation_W"] = nullptr;
    if (d.bits > 0 && !d.saturation_W)
      r.fail("saturation_W", "is required when bits > 0: the digitiser's full scale");
  };
  read_fields(r, {{"saturation_W", check_saturation}}, d);
  r.finish();
  return d;
}

}  // namespace glaswave
