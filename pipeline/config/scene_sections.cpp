// The readers of what a shot sees and how it is traced (their keys: scene_keys.cpp):
// `simulation`, `terrain`, `canopy` (shared with the stands file), `track`.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "canopy/vegetation_traits.hpp"
#include "core/error.hpp"
#include "core/glas_time.hpp"
#include "core/names.hpp"
#include "core/part_kind.hpp"
#include "pipeline/config/json_reader.hpp"
#include "pipeline/config/keys.hpp"
#include "pipeline/config/section_readers.hpp"

namespace glaswave {

using nlohmann::json;

namespace {

constexpr double wgs84_equatorial_radius_m = 6378137.0;

// An ISO 8601 time of the configuration, as seconds since the GLAS epoch.
double time_s(JsonReader& reader, const std::string& key, const std::string& text) {
  try {
    return parse_iso8601_utc(text);
  } catch (const std::invalid_argument& e) {
    reader.fail(key, e.what());
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

}  // namespace

SimulationSettings read_simulation(JsonReader& root) {
  SimulationSettings s;
  JsonReader r = root.object("simulation");
  read_fields(r, {{"background", [&] { read_background(r, s); }}}, s);
  r.finish();
  return s;
}

namespace {

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

}  // namespace

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

namespace {

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

// canopy.<kind>: the object of a kind that declared itself (VegetationTraits), alone in the
// canopy, read with the keys its declaration names.
CanopySettings read_kind_canopy(JsonReader& canopy, const std::string& kind,
                                VegetationTraits::Keys keys, const std::vector<LidarBand>& bands) {
  for (const std::string& key : canopy.given())
    if (key != kind)
      canopy.fail(key, "cannot be given beside canopy." + kind +
                           " (the canopy holds one vegetation source)");
  CanopySettings c;
  c.kind = kind;
  JsonReader r = canopy.object(kind);
  KeyHooks hooks;
  if (keys == VegetationTraits::Keys::measured) {
    hooks = leaf_hooks(r, c, bands);
    hooks.emplace_back("bark_fraction", [&] { c.green_fraction = 1.0 - c.bark_fraction; });
  } else if (keys == VegetationTraits::Keys::facets) {
    hooks = {{"models", [&] { c.facet_models = r.path_map("models"); }},
             {"materials", [&] { read_facet_materials(r, c, bands); }}};
  }
  read_fields(r, hooks, c);
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
  // The kind whose object is given; else the crowns' (the vegetation sources declare their kinds).
  for (const auto& kind : Registry<PartKind<VegetationTraits>>::instance().entries())
    if (kind.make.traits.keys != VegetationTraits::Keys::crowns && r.has(kind.name))
      return read_kind_canopy(r, kind.name, kind.make.traits.keys, bands);
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

}  // namespace

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

}  // namespace glaswave
