// The configuration parser: JSON document -> typed settings, each key read with its default and
// range next to the member it sets (PDAL style), presets expanded, every error at its JSON path.
#include "pipeline/config/config.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "core/error.hpp"
#include "core/glas_time.hpp"
#include "core/names.hpp"
#include "pipeline/config/atmosphere_presets.hpp"
#include "pipeline/config/canopy_section.hpp"
#include "pipeline/config/cross_checks.hpp"
#include "pipeline/config/json_reader.hpp"
#include "pipeline/config/json_text.hpp"
#include "pipeline/config/keys.hpp"
#include "pipeline/config/presets.hpp"
#include "pipeline/config/stands_file.hpp"

namespace glaswave {

using nlohmann::json;

namespace {

constexpr double wgs84_equatorial_radius_m = 6378137.0;

// ---- spectral properties --------------------------------------------------------------------

std::string band_list(const std::vector<LidarBand>& bands) {
  std::string list;
  for (std::size_t i = 0; i < bands.size(); ++i) list += (i ? ", " : "") + bands[i].name;
  return list;
}

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

// An ISO 8601 time of the configuration, as seconds since the GLAS epoch.
double time_s(JsonReader& reader, const std::string& key, const std::string& text) {
  try {
    return parse_iso8601_utc(text);
  } catch (const std::invalid_argument& e) {
    reader.fail(key, e.what());
  }
}

// ---- sections -------------------------------------------------------------------------------

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

// The beams of the photon-counting receiver: ATLAS's, one a run for now.
void check_beams(JsonReader& r, SensorSettings& s) {
  // Given empty, it asks for no beam: gt2l in its place would run without a word.
  if (s.beams.empty() && r.has("beams"))
    r.fail("beams",
           "names no beam: name one or more of gt1l gt1r gt2l gt2r gt3l gt3r, or leave it out "
           "for gt2l");
  if (s.beams.empty()) s.beams = SensorSettings{}.beams;
  r.resolved()["beams"] = s.beams;
  if (s.receiver != "photon_counting") return;
  static const std::vector<std::string> known = {"gt1l", "gt1r", "gt2l", "gt2r", "gt3l", "gt3r"};
  for (const std::string& beam : s.beams)
    if (std::find(known.begin(), known.end(), beam) == known.end())
      r.fail("beams", "no beam \"" + beam + "\"; the beams are gt1l gt1r gt2l gt2r gt3l gt3r" +
                          did_you_mean(beam, known));
  for (auto beam = s.beams.begin(); beam != s.beams.end(); ++beam)
    if (std::find(s.beams.begin(), beam, *beam) != beam)
      r.fail("beams", "names \"" + *beam + "\" twice: its shots would be simulated twice");
}

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

// Photon counting's background light: "sun", "none" or {"rate_MHz": R}.
void read_background(JsonReader& r, SimulationSettings& s) {
  const json& background = r.raw("background");
  if (background.is_object()) {
    JsonReader b(background, r.place("background"), r.resolved()["background"],
                 r.declared("background", KeyType::choice_or_object));
    s.background = "rate";
    s.background_rate_MHz = b.number("rate_MHz");
    b.finish();
  } else if (background.is_null() || background == "sun" || background == "none") {
    s.background = background.is_null() ? "sun" : background.get<std::string>();
    r.resolved()["background"] = s.background;
  } else {
    r.fail("background",
           "must be \"sun\", \"none\" or {\"rate_MHz\": R}, got " + describe(background));
  }
}

SimulationSettings read_simulation(JsonReader& root) {
  SimulationSettings s;
  JsonReader r = root.object("simulation");
  read_fields(r, {{"background", [&] { read_background(r, s); }}}, s);
  r.finish();
  return s;
}

// Exactly one of "dem", "plane" and "point_cloud"; the plane and the cloud's flag are read as
// their keys come. A point cloud's ground beside another ground is refused at its own key.
void read_dem(JsonReader& r, TerrainSettings& t) {
  const std::optional<std::string> dem = r.optional_string("dem");
  const bool has_plane = r.has("plane"), has_cloud = r.has("point_cloud");
  if (has_cloud && (dem || has_plane))
    r.fail("point_cloud", std::string("cannot be given beside terrain.") + (dem ? "dem" : "plane") +
                              ": the ground is one of \"dem\", \"plane\" and \"point_cloud\"");
  if (dem && has_plane)
    throw config_error(r.path(), "give exactly one of \"dem\" and \"plane\", not both");
  if (!dem && !has_plane && !has_cloud)
    throw config_error(r.path(), "give exactly one of \"dem\", \"plane\" and \"point_cloud\"");
  if (dem && dem->empty()) r.fail("dem", "must not be empty");
  t.dem = dem.value_or("");
}

// terrain.point_cloud: true or absent (false would leave no ground), as its declaration's `only`
// says for the schema and the reference.
void check_point_cloud_terrain(JsonReader& r, const TerrainSettings& t) {
  const Key& declared = r.declared("point_cloud", KeyType::boolean);
  if (t.point_cloud && nlohmann::json(*t.point_cloud) != declared.only)
    r.fail("point_cloud",
           "must be true (the ground of canopy.point_cloud's cloud); give \"dem\" or \"plane\" "
           "instead of false");
}

// The DEM's band of heights, required by the terrain when it has several.
void read_dem_band(JsonReader& r, TerrainSettings& t) {
  if (!r.has("dem_band")) return;
  if (t.dem.empty()) r.fail("dem_band", "applies to terrain.dem only");
  t.dem_band = static_cast<int>(*r.optional_integer("dem_band"));
}

// What the DEM's heights are measured from when its CRS does not say; a plane's heights are
// above the ellipsoid.
void read_vertical_datum(JsonReader& r, TerrainSettings& t) {
  const Key& datum = r.declared("vertical_datum", KeyType::string);
  t.vertical_datum_given = r.has("vertical_datum");
  t.vertical_datum = r.string("vertical_datum");
  if (std::find(datum.choices.begin(), datum.choices.end(), t.vertical_datum) ==
          datum.choices.end() &&
      t.vertical_datum.find(datum.pattern) == std::string::npos) {
    std::string message = "must be ";
    for (const std::string& name : datum.choices) message += "\"" + name + "\", ";
    message.resize(message.size() - 2);
    message += " or a vertical CRS such as \"EPSG:3855\", got \"" + t.vertical_datum + "\"";
    r.fail("vertical_datum", message + did_you_mean(t.vertical_datum, datum.choices));
  }
  if (t.dem.empty() && !t.point_cloud && t.vertical_datum != datum.default_value.get<std::string>())
    r.fail("vertical_datum",
           "applies to terrain.dem and terrain.point_cloud only: a plane's elevation_m is above "
           "the WGS84 ellipsoid");
}

// The terrain, which the caller has seen to be given.
TerrainSettings read_terrain(JsonReader& root, const std::vector<LidarBand>& bands) {
  TerrainSettings t;
  JsonReader r = root.object("terrain");
  read_fields(
      r,
      {{"dem", [&] { read_dem(r, t); }},
       {"point_cloud", [&] { check_point_cloud_terrain(r, t); }},
       {"dem_band", [&] { read_dem_band(r, t); }},
       {"vertical_datum", [&] { read_vertical_datum(r, t); }},
       {"soil_reflectance", [&] { t.soil_reflectance = spectral(r, "soil_reflectance", bands); }}},
      t);
  r.finish();
  return t;
}

void read_lad(JsonReader& r, CanopySettings& c) {
  static const std::vector<std::pair<std::string, LeafAngleDistribution>> names = {
      {"spherical", LeafAngleDistribution::spherical},
      {"planophile", LeafAngleDistribution::planophile},
      {"erectophile", LeafAngleDistribution::erectophile},
      {"plagiophile", LeafAngleDistribution::plagiophile},
      {"extremophile", LeafAngleDistribution::extremophile},
      {"uniform", LeafAngleDistribution::uniform}};
  const json& value = r.raw("lad");
  if (value.is_object()) {
    JsonReader e(value, r.place("lad"), r.resolved()["lad"],
                 r.declared("lad", KeyType::choice_or_object));
    c.lad = LeafAngleDistribution::ellipsoidal;
    c.lad_mean_deg = e.number("ellipsoidal_mean_deg");
    e.finish();
    return;
  }
  if (!value.is_null() && !value.is_string()) {
    r.fail("lad", "must be a name or {\"ellipsoidal_mean_deg\": X}, got " + describe(value));
  }
  const Key& declared = r.declared("lad", KeyType::choice_or_object);
  const std::string name =
      value.is_string() ? value.get<std::string>() : declared.default_value.get<std::string>();
  if (std::find(declared.choices.begin(), declared.choices.end(), name) != declared.choices.end()) {
    for (const auto& [known, lad] : names) {
      if (known == name) {
        c.lad = lad;
        r.resolved()["lad"] = name;
        return;
      }
    }
  }
  std::string list;
  for (const std::string& known : declared.choices) list += known + ", ";
  r.fail("lad", "must be one of " + list + "or {\"ellipsoidal_mean_deg\": X}, got " +
                    describe(value) + did_you_mean(name, declared.choices));
}

// A fraction that is the complement of a value the user gave: rounded to 12 decimals so that
// 1 - 0.8 reads 0.2 in the resolved configuration, not 0.19999999999999996.
double complement(double x) { return std::round((1.0 - x) * 1e12) / 1e12; }

// Giving one of the green and bark fractions implies the other; giving both asks that they add
// up.
void read_fractions(JsonReader& r, CanopySettings& c) {
  if (r.has("bark_fraction") && !r.has("green_fraction")) {
    c.bark_fraction = r.number("bark_fraction");
    c.green_fraction = r.number("green_fraction", complement(c.bark_fraction));
  } else {
    const bool green_given = r.has("green_fraction");
    c.green_fraction = r.number("green_fraction");
    c.bark_fraction = green_given ? r.number("bark_fraction", complement(c.green_fraction))
                                  : r.number("bark_fraction");
  }
  const double fraction_sum = c.green_fraction + c.bark_fraction;
  if (std::fabs(fraction_sum - 1.0) > 1e-9)
    r.fail("bark_fraction",
           "green_fraction + bark_fraction must be 1, got " + format_number(fraction_sum));
}

// The heights of the crowns' bases, [min, max].
void read_crown_base(JsonReader& r, CanopySettings& c) {
  const json& base = r.raw("crown_base_m");
  if (!base.is_null()) {
    if (!base.is_array() || base.size() != 2)
      r.fail("crown_base_m", "must be an array of 2 numbers [min, max], got " + describe(base));
    for (std::size_t i = 0; i < 2; ++i)
      c.crown_base_m[i] =
          read_number(r.place("crown_base_m") + "/" + std::to_string(i), base[i], at_least(0));
    if (c.crown_base_m[0] > c.crown_base_m[1])
      r.fail("crown_base_m", "min must be <= max, got " + describe(base));
  }
  r.resolved()["crown_base_m"] = base.is_null() ? json(c.crown_base_m) : base;
}

// Crowns placed at random overlap: their cover 1 - exp(-n pi r^2) never reaches 1.
void check_crown_cover(JsonReader& r, const CanopySettings& c) {
  if (c.crown_shape != CrownShape::layer && c.cover >= 1.0)
    r.fail(
        "cover",
        "must be < 1 for randomly placed crowns, got 1; a closed canopy is crown_shape \"layer\"");
}

// Energy conservation of a bi-Lambertian leaf: what is not reflected or transmitted is absorbed.
void check_leaf_optics(JsonReader& r, const CanopySettings& c,
                       const std::vector<LidarBand>& bands) {
  for (std::size_t i = 0; i < bands.size(); ++i) {
    const double sum = c.leaf_reflectance[i] + c.leaf_transmittance[i];
    if (sum > 1.0 + 1e-12) {
      r.fail("leaf_transmittance", "leaf_reflectance + leaf_transmittance must be <= 1 in band " +
                                       bands[i].name + ", got " + format_number(sum));
    }
  }
}

// The keys every canopy's leaves have (crowns, voxels, point clouds): the leaf angle
// distribution and the optical properties of leaves and bark, per band.
KeyHooks leaf_hooks(JsonReader& r, CanopySettings& c, const std::vector<LidarBand>& bands) {
  return {
      {"lad", [&] { read_lad(r, c); }},
      {"leaf_reflectance", [&] { c.leaf_reflectance = spectral(r, "leaf_reflectance", bands); }},
      {"leaf_transmittance",
       [&] {
         c.leaf_transmittance = spectral(r, "leaf_transmittance", bands);
         check_leaf_optics(r, c, bands);
       }},
      {"bark_reflectance", [&] { c.bark_reflectance = spectral(r, "bark_reflectance", bands); }}};
}

// canopy.voxels or canopy.point_cloud: measured vegetation, alone in the canopy.
CanopySettings read_measured_canopy(JsonReader& canopy, const std::vector<LidarBand>& bands) {
  const bool voxels = canopy.has("voxels");
  const char* name = voxels ? "voxels" : "point_cloud";
  for (const std::string& key : canopy.given())
    if (key != name)
      canopy.fail(key, std::string("cannot be given beside canopy.") + name +
                           " (the canopy holds one vegetation source)");
  CanopySettings c;
  c.kind = name;
  JsonReader r = canopy.object(name);
  KeyHooks hooks = leaf_hooks(r, c, bands);
  hooks.emplace_back("bark_fraction", [&] { c.green_fraction = 1.0 - c.bark_fraction; });
  read_fields(r, hooks, c);
  r.finish();
  return c;
}

// canopy.facets.materials: each material's optics per band, a leaf where a transmittance is given.
void read_facet_materials(JsonReader& r, CanopySettings& c, const std::vector<LidarBand>& bands) {
  for (auto& [name, entry] : r.object_map("materials")) {
    FacetMaterialSettings m;
    m.name = name;
    entry.require("reflectance");
    m.reflectance = spectral(entry, "reflectance", bands);
    m.leaf = entry.has("transmittance");
    m.transmittance =
        m.leaf ? spectral(entry, "transmittance", bands) : std::vector<double>(bands.size(), 0.0);
    for (std::size_t i = 0; i < bands.size(); ++i)
      if (m.reflectance[i] + m.transmittance[i] > 1.0 + 1e-12)
        entry.fail("transmittance", "reflectance + transmittance must be <= 1 in band " +
                                        bands[i].name + ", got " +
                                        format_number(m.reflectance[i] + m.transmittance[i]));
    entry.finish();
    c.facet_materials.push_back(std::move(m));
  }
}

// canopy.facets: facet trees, alone in the canopy.
CanopySettings read_facet_canopy(JsonReader& canopy, const std::vector<LidarBand>& bands) {
  for (const std::string& key : canopy.given())
    if (key != "facets")
      canopy.fail(key,
                  "cannot be given beside canopy.facets (the canopy holds one vegetation "
                  "source)");
  CanopySettings c;
  c.kind = "facets";
  JsonReader r = canopy.object("facets");
  read_fields(r,
              {{"models", [&] { c.facet_models = r.path_map("models"); }},
               {"materials", [&] { read_facet_materials(r, c, bands); }}},
              c);
  r.finish();
  return c;
}

}  // namespace

std::optional<CanopySettings> read_canopy(JsonReader& root, const std::vector<LidarBand>& bands) {
  if (!root.has("canopy")) {
    root.resolved()["canopy"] = nullptr;  // bare ground
    return std::nullopt;
  }
  JsonReader r = root.object("canopy");
  if (r.has("voxels") || r.has("point_cloud")) return read_measured_canopy(r, bands);
  if (r.has("facets")) return read_facet_canopy(r, bands);
  CanopySettings c;
  KeyHooks hooks = leaf_hooks(r, c, bands);
  hooks.insert(hooks.end(), {{"green_fraction", [&] { read_fractions(r, c); }},
                             {"crown_shape", [&] { check_crown_cover(r, c); }},
                             {"crown_base_m", [&] { read_crown_base(r, c); }}});
  read_fields(r, hooks, c);
  r.finish();
  return c;
}

namespace {

// The ground points of a "points" track, one shot each.
void read_points(JsonReader& r, TrackSettings& t, bool shots_given) {
  const bool points_type = t.type == TrackType::points;
  for (JsonReader& p : r.object_array("points", points_type)) {
    GroundPoint point;
    point.lat_deg = p.number("lat_deg");
    point.lon_deg = p.number("lon_deg");
    p.finish();
    t.points.push_back(point);
  }
  if (points_type) {
    const auto count = static_cast<std::int64_t>(t.points.size());
    if (shots_given && t.shots != count) {
      r.fail("shots", "must equal the number of points (" + std::to_string(count) +
                          ") when type is \"points\", got " + std::to_string(t.shots));
    }
    t.shots = count;
    r.resolved()["shots"] = count;
  }
}

// Keplerian elements sit flat in `track`, as the product contract lists them. Elements without
// an epoch are taken to hold at the first shot.
void read_epoch(JsonReader& r, TrackSettings& t, const std::string& start_time) {
  OrbitElements& o = t.orbit;
  const std::string epoch = r.string("epoch", start_time);
  o.epoch_s = time_s(r, "epoch", epoch);
  if (t.type != TrackType::orbit) return;
  const double perigee_m = o.semi_major_axis_m * (1.0 - o.eccentricity);
  if (perigee_m <= wgs84_equatorial_radius_m) {
    r.fail("eccentricity", "puts the perigee (" + format_number(perigee_m) +
                               " m from the Earth's centre) inside the Earth");
  }
  const double apogee_height_m =
      o.semi_major_axis_m * (1.0 + o.eccentricity) - wgs84_equatorial_radius_m;
  if (apogee_height_m > run_limits::altitude_m)
    r.fail("eccentricity", "puts the apogee " + format_number(apogee_height_m) +
                               " m high, above the limit of " +
                               format_number(run_limits::altitude_m) + " m");
}

TrackSettings read_track(JsonReader& root, const SensorSettings& sensor) {
  TrackSettings t;
  JsonReader r = root.object("track");
  std::string start_time;
  const auto read_start_time = [&] {
    start_time = r.string("start_time");
    t.start_time_s = time_s(r, "start_time", start_time);
  };
  const auto ephemeris_given = [&] {
    if (t.type == TrackType::ephemeris && t.ephemeris.empty())
      r.fail("ephemeris", "is required when type is \"ephemeris\"");
  };
  const auto granule_given = [&] {
    if (t.type == TrackType::granule && t.granule.empty())
      r.fail("file", "is required when type is \"granule\"");
  };
  read_fields(r,
              {{"start_time", read_start_time},
               {"points", [&] { read_points(r, t, r.has("shots")); }},
               {"epoch", [&] { read_epoch(r, t, start_time); }},
               {"ephemeris", ephemeris_given},
               {"beams", granule_given}},
              t, t.orbit);
  // A track fires at its laser's rate unless it says otherwise (ATLAS's 10 kHz, not GLAS's 40).
  if (!r.has("rate_hz")) {
    t.rate_hz = sensor.pulse_rate_hz;
    r.resolved()["rate_hz"] = sensor.pulse_rate_hz;
  }
  r.finish();
  return t;
}

// output.geojson is the old name of output.footprints (which also writes a GeoPackage): read
// into it with a warning, and written into the resolved configuration under the new name.
void read_old_footprints_key(JsonReader& r, OutputSettings& o, std::vector<std::string>& warnings) {
  if (!r.has("geojson")) return;
  if (r.has("footprints"))
    r.fail("geojson", "is the old name of output.footprints: give footprints alone");
  o.footprints = r.boolean("geojson");
  r.resolved().erase("geojson");
  r.resolved()["footprints"] = o.footprints;
  warnings.push_back(r.place("geojson") +
                     ": is now output.footprints (the old name still works, for now)");
}

OutputSettings read_output(JsonReader& root, std::vector<std::string>& warnings) {
  OutputSettings o;
  JsonReader r = root.object("output");
  read_fields(r, {{"geojson", [&] { read_old_footprints_key(r, o, warnings); }}}, o);
  for (const auto& entry : Registry<PartSwitch>::instance().entries())  // declared by the parts
    if (entry.make.section == "output") o.switches[entry.name] = r.boolean(entry.name);
  r.finish();
  return o;
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

BrfSettings read_brf(JsonReader& root) {
  BrfSettings b;
  JsonReader r = root.object("brf");
  read_fields(r, {}, b);
  r.finish();
  return b;
}

TableSettings read_table(JsonReader& root) {
  TableSettings t;
  JsonReader r = root.object("table");
  // An object of at least one entry, or absent.
  const auto entries_of = [&](const std::string& key) -> const json* {
    const json& value = r.raw(key);
    if (value.is_null()) return nullptr;
    if (!value.is_object() || value.empty())
      r.fail(key, "must be an object of at least one key, got " + describe(value));
    return &value;
  };
  const auto read_vary = [&] {
    const json* vary = entries_of("vary");
    if (!vary) return;
    for (const auto& [name, range] : vary->items()) {
      const std::string place = json_pointer_child(r.place("vary"), name);
      if (!range.is_array() || range.size() != 2)
        throw config_error(place, "must be [low, high], got " + describe(range));
      const double low = read_number(place + "/0", range[0], any_finite());
      const double high = read_number(place + "/1", range[1], any_finite());
      if (!(low <= high)) throw config_error(place, "must be [low, high] with low <= high");
      t.vary.push_back({name, {low, high}});
      r.resolved()["vary"][name] = range;
    }
  };
  const auto read_values = [&] {
    const json* values = entries_of("values");
    if (!values) return;
    for (const auto& [name, list] : values->items()) {
      const std::string place = json_pointer_child(r.place("values"), name);
      if (!list.is_array() || list.empty())
        throw config_error(place, "must be an array of at least one value, got " + describe(list));
      std::vector<std::string> texts;
      for (const json& value : list) {
        if (!value.is_string() || value.get<std::string>().empty())
          throw config_error(place,
                             "each value must be a non-empty string (read as --set reads "
                             "VALUE), got " +
                                 describe(value));
        texts.push_back(value.get<std::string>());
      }
      t.values.push_back({name, std::move(texts)});
      r.resolved()["values"][name] = list;
    }
  };
  read_fields(r, {{"vary", read_vary}, {"values", read_values}}, t);
  r.finish();
  for (const auto& [name, range] : t.vary)
    for (const auto& [other, list] : t.values)
      if (name == other)
        r.fail("values", "`" + name + "` is both varied over a range and given values");
  return t;
}

}  // namespace

ShotSize shot_size(const Config& c) {
  ShotSize size;
  size.bands = static_cast<double>(c.sensor.bands.size());
  size.window_bins = c.sensor.bins;
  size.margin_bins = 2.0 * pulse_margin_bins(c.sensor);
  size.waveforms = 3.0 + (c.output.per_order ? c.simulation.max_order : 0);
  size.bytes = size.bands * (size.window_bins + size.margin_bins) * size.waveforms * 8.0;
  return size;
}

std::string mebibytes(double bytes) {
  return format_number(std::round(bytes / 1048576.0 * 10) / 10) + " MiB";
}

namespace {

// A run holds a shot's waveforms many times over (the transport tallies each shot's rays in 65
// copies, and every thread simulates a shot): one shot's must stay small. Refused beyond the
// limit, at the key that makes it large.
void check_shot_size(const Config& c) {
  const ShotSize size = shot_size(c);
  if (size.bytes <= run_limits::shot_waveform_bytes) return;
  std::string place = "/sensor/bins";
  if (size.margin_bins > size.window_bins) place = "/sensor/pulse_sigma_ns";
  if (c.output.per_order && size.waveforms > 3.0 &&
      size.bytes * 3.0 / size.waveforms <= run_limits::shot_waveform_bytes)
    place = "/output/per_order";
  std::ostringstream why;
  why << "a shot's waveforms would take " << mebibytes(size.bytes) << " ("
      << format_number(size.bands) << " bands x " << format_number(size.window_bins) << " bins + "
      << format_number(size.margin_bins) << " bins of pulse margin x "
      << format_number(size.waveforms) << " waveforms x 8 bytes), more than the limit of "
      << mebibytes(run_limits::shot_waveform_bytes) << " a shot";
  throw config_error(place, why.str());
}

// A relative path of the configuration is taken relative to the configuration file's folder, so
// that a configuration runs the same from any working directory.
void resolve_path(std::string& path, json& resolved_section, const char* key,
                  const std::filesystem::path& folder) {
  if (path.empty() || std::filesystem::path(path).is_absolute()) return;
  path = std::filesystem::absolute(folder / path).lexically_normal().string();
  resolved_section[key] = path;
}

}  // namespace

Config parse_config(const json& document) {
  if (!document.is_object())
    throw config_error("", "the configuration must be a JSON object, got " + describe(document));
  Config c;
  c.resolved = json::object();
  JsonReader root(document, "", c.resolved, configuration_keys());
  root.optional_string("$schema");  // lets an editor find the schema; not a setting
  c.seed = root.unsigned_integer("seed");
  // The sensor first: its bands give the per-band optical properties their length.
  c.sensor = read_sensor(root);
  c.atmosphere = read_atmosphere(root, c.sensor.bands);
  if (c.atmosphere) set_band_transmissions(c.sensor, *c.atmosphere);
  c.simulation = read_simulation(root);
  // A missing terrain is told after every other section is read and the unknown keys are
  // refused, so that a wrong value given ({"canopy": {"pai": -1}}) or a misspelt "terrian" is
  // named before the section not given.
  const bool terrain_given = root.has("terrain");
  if (terrain_given) c.terrain = read_terrain(root, c.sensor.bands);
  c.canopy = read_canopy(root, c.sensor.bands);
  c.track = read_track(root, c.sensor);
  c.output = read_output(root, c.warnings);
  // The ICESat-2 granules are the photon-counting receiver's: asked of the waveform's, nothing.
  if (c.sensor.receiver != "photon_counting")
    for (const auto& [key, asked] : {std::pair{"atl03", c.output.atl03}, {"atl08", c.output.atl08}})
      if (asked.value_or(false))
        c.warnings.push_back("/output/" + std::string(key) + ": the " + c.sensor.receiver +
                             " receiver writes no ICESat-2 granule; it is written with "
                             "sensor.receiver \"photon_counting\"");
  c.detector = read_detector(root);
  c.brf = read_brf(root);
  c.table = read_table(root);
  root.finish();
  if (!terrain_given)
    root.fail("terrain", "is required: give \"dem\", \"plane\" or \"point_cloud\"");
  c.resolved.erase("$schema");
  check_across_keys(document, c);
  check_shot_size(c);
  return c;
}

namespace {

// RAMI-IV's lidar measurements: names ROMC knows, a model and experiment that make file names, and
// height bins that hold whole window bins.
void check_rami_lidar(const Config& config) {
  const RamiLidarSettings& rami = *config.output.rami;
  if (rami.measurements.empty())
    throw config_error("/output/rami/measurements", "names no measurement");
  for (const std::string& m : rami.measurements) {
    if (m != "lidar_sgl_co" && m != "lidar_tot")
      throw config_error("/output/rami/measurements",
                         "'" + m +
                             "' is not a lidar measurement glaswave writes (lidar_sgl_co, "
                             "lidar_tot)");
    if (m == "lidar_sgl_co" && !config.output.per_order)
      throw config_error("/output/per_order",
                         "lidar_sgl_co is the light scattered once: output.rami needs "
                         "output.per_order true for it");
  }
  const std::string model = rami.model.empty() ? "glaswave" : rami.model;  // absent: its default
  if (model.size() > 10 || !std::all_of(model.begin(), model.end(),
                                        [](unsigned char c) { return std::isalnum(c) != 0; }))
    throw config_error("/output/rami/model",
                       "ROMC's model identifier is 1 to 10 letters and digits");
  if (rami.experiment.empty()) throw config_error("/output/rami/experiment", "is required");
  if (rami.experiment.find_first_of("/\\ ") != std::string::npos)
    throw config_error("/output/rami/experiment",
                       "must not hold '/', '\\' or spaces (a file name)");
  if (config.sensor.bands.size() > 1 && rami.experiment.find("{band}") == std::string::npos)
    throw config_error("/output/rami/experiment",
                       "needs '{band}' with more than one band: an experiment is one band's");
  if (config.sensor.receiver != "waveform")
    throw config_error("/output/rami", "RAMI's lidar measurements need the waveform receiver");
  if (config.atmosphere)
    throw config_error("/output/rami",
                       "RAMI's lidar measurements are of the canopy alone: not beside "
                       "`atmosphere`");
  if (config.detector.enabled)
    throw config_error("/output/rami",
                       "RAMI's lidar measurements are the noise-free return: not with "
                       "detector.enabled");
  // A window bin spans c bin_ns / 2 of height at nadir.
  const double window_bin_m = 0.5 * 299792458.0 * config.sensor.bin_ns * 1e-9;
  const double ratio = rami.height_bin_m / window_bin_m;
  if (ratio < 1.0 - 1e-6 || std::abs(ratio - std::round(ratio)) > 1e-6 * ratio) {
    char why[240];
    std::snprintf(why, sizeof why,
                  "%.6g m is not a whole number of the window's bins of %.6g m (c bin_ns / 2); "
                  "sensor.bin_ns %.9g gives 10 of them",
                  rami.height_bin_m, window_bin_m,
                  rami.height_bin_m / 10.0 * 2.0 / 299792458.0 * 1e9);
    throw config_error("/output/rami/height_bin_m", why);
  }
}

}  // namespace

void check_outputs(const Config& config) {
  const OutputSettings& o = config.output;
  // A photon-counting run's ICESat-2 granules are products of their own.
  const bool granules = config.sensor.receiver == "photon_counting" &&
                        (o.atl03.value_or(true) || o.atl08.value_or(true));
  if (!o.netcdf && !o.footprints && !granules && !o.rami)
    throw config_error("/output",
                       "nothing to write: output.netcdf and output.footprints are both false");
  if (o.plots && !(o.netcdf && o.footprints))
    throw config_error(
        "/output/plots",
        "plots are drawn from shots.nc and footprints.geojson: they need output.netcdf "
        "and output.footprints");
  if (o.plots && !o.metrics)
    throw config_error("/output/metrics",
                       "plots draw the Gaussian fits and ground estimates: output.plots needs "
                       "output.metrics");
  if (o.plots && o.footprints_format != "GeoJSON")
    throw config_error("/output/footprints_format",
                       "plots are drawn from footprints.geojson: output.plots needs "
                       "footprints_format \"GeoJSON\", got \"" +
                           o.footprints_format + "\"");
  if (o.rami) check_rami_lidar(config);
}

Config load_config(const std::filesystem::path& file, const std::vector<std::string>& overrides) {
  return load_config_document(read_json_file(file), file.parent_path(), overrides);
}

Config load_config_document(json document, const std::filesystem::path& folder,
                            const std::vector<std::string>& overrides) {
  for (const std::string& assignment : overrides) apply_override(document, assignment);
  Config c = parse_config(document);
  json& r = c.resolved;
  resolve_path(c.terrain.dem, r["terrain"], "dem", folder);
  if (c.canopy) {
    resolve_path(c.canopy->crowns_file, r["canopy"], "crowns_file", folder);
    resolve_path(c.canopy->stands, r["canopy"], "stands", folder);
    if (!c.canopy->voxels_file.empty())
      resolve_path(c.canopy->voxels_file, r["canopy"]["voxels"], "file", folder);
    if (!c.canopy->point_cloud_file.empty())
      resolve_path(c.canopy->point_cloud_file, r["canopy"]["point_cloud"], "file", folder);
    if (!c.canopy->facet_trees_file.empty()) {
      json& facets = r["canopy"]["facets"];
      resolve_path(c.canopy->facet_trees_file, facets, "trees_file", folder);
      for (auto& [name, file] : c.canopy->facet_models)
        resolve_path(file, facets["models"], name.c_str(), folder);
    }
  }
  resolve_path(c.track.ephemeris, r["track"], "ephemeris", folder);
  resolve_path(c.track.granule, r["track"], "file", folder);
  if (c.canopy && !c.canopy->stands.empty())
    c.canopy->stand_areas = read_stands(c.canopy->stands, r["canopy"], c.sensor.bands);
  return c;
}

}  // namespace glaswave
