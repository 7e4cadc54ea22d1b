// The declaration of every configuration key, and what is generated from it: the JSON Schema
// and the README's table of keys. Defaults that the settings structs already hold are taken
// from their member initialisers, so that each default is written once.
#include "pipeline/config/keys.hpp"

#include <sstream>
#include <type_traits>
#include <typeinfo>

#include "canopy/canopy_settings.hpp"
#include "core/part_switch.hpp"
#include "footprints/atmosphere_settings.hpp"
#include "footprints/track_settings.hpp"
#include "pipeline/config/atmosphere_presets.hpp"
#include "pipeline/config/config.hpp"
#include "pipeline/config/json_reader.hpp"
#include "pipeline/config/presets.hpp"
#include "terrain/terrain_settings.hpp"

namespace glaswave {

using nlohmann::json;

// ---- ranges ---------------------------------------------------------------------------------

bool Range::contains(double x) const {
  if (low && (low_open ? !(x > *low) : !(x >= *low))) return false;
  if (high && (high_open ? !(x < *high) : !(x <= *high))) return false;
  return true;
}

std::string Range::requirement() const {
  if (low && high) {
    return "must be in " + std::string(low_open ? "(" : "[") + format_number(*low) + ", " +
           format_number(*high) + (high_open ? ")" : "]");
  }
  if (low) return std::string("must be ") + (low_open ? "> " : ">= ") + format_number(*low);
  if (high) return std::string("must be ") + (high_open ? "< " : "<= ") + format_number(*high);
  return "";
}

std::string Range::interval() const {
  if (low && high) {
    return std::string(low_open ? "(" : "[") + format_number(*low) + ", " + format_number(*high) +
           (high_open ? ")" : "]");
  }
  if (low) return (low_open ? "> " : "≥ ") + format_number(*low);
  if (high) return (high_open ? "< " : "≤ ") + format_number(*high);
  return "";
}

Range any_finite() { return Range{}; }
Range at_least(double low) { return Range{low, std::nullopt, false, false}; }
Range above(double low) { return Range{low, std::nullopt, true, false}; }
Range closed(double low, double high) { return Range{low, high, false, false}; }
Range half_open(double low, double high) { return Range{low, high, false, true}; }
Range open_closed(double low, double high) { return Range{low, high, true, false}; }
Range open(double low, double high) { return Range{low, high, true, true}; }

// ---- builders -------------------------------------------------------------------------------

const Key* Key::child(const std::string& key) const {
  for (const Key& c : children)
    if (c.name == key) return &c;
  return nullptr;
}

Key&& Key::with_required() && {
  required = true;
  return std::move(*this);
}
Key&& Key::with_nullable() && {
  nullable = true;
  return std::move(*this);
}
Key&& Key::with_default_text(std::string text) && {
  default_text = std::move(text);
  return std::move(*this);
}
Key&& Key::with_items(std::size_t least, std::size_t most) && {
  min_items = least;
  max_items = most;
  return std::move(*this);
}
Key&& Key::with_default(json value) && {
  default_value = std::move(value);
  return std::move(*this);
}
Key&& Key::with_only(json value) && {
  only = std::move(value);
  return std::move(*this);
}

namespace {

Key make(std::string name, KeyType type, std::string unit, std::string description) {
  Key k;
  k.name = std::move(name);
  k.type = type;
  k.unit = std::move(unit);
  k.description = std::move(description);
  return k;
}

}  // namespace

namespace declare {

Key number(std::string name, std::optional<double> fallback, Range range, std::string unit,
           std::string description) {
  Key k = make(std::move(name), KeyType::number, std::move(unit), std::move(description));
  if (fallback) k.default_value = *fallback;
  k.nullable = !fallback;  // a number without a default may be null: not set
  k.range = range;
  return k;
}

Key integer(std::string name, std::optional<std::int64_t> fallback, std::int64_t min,
            std::uint64_t max, std::string unit, std::string description) {
  Key k = make(std::move(name), KeyType::integer, std::move(unit), std::move(description));
  if (fallback) k.default_value = *fallback;
  k.min = min;
  k.max = max;
  return k;
}

Key boolean(std::string name, bool fallback, std::string description) {
  Key k = make(std::move(name), KeyType::boolean, "", std::move(description));
  k.default_value = fallback;
  return k;
}

Key string(std::string name, std::optional<std::string> fallback, std::string description) {
  Key k = make(std::move(name), KeyType::string, "", std::move(description));
  if (fallback) k.default_value = *fallback;
  k.nullable = !fallback;
  return k;
}

Key choice(std::string name, std::optional<std::string> fallback, std::vector<std::string> choices,
           std::string description) {
  Key k = string(std::move(name), std::move(fallback), std::move(description));
  k.choices = std::move(choices);
  return k;
}

Key time(std::string name, std::optional<std::string> fallback, std::string description) {
  Key k = string(std::move(name), std::move(fallback), std::move(description));
  k.format = "date-time";
  return k;
}

Key path(std::string name, std::string description) {
  Key k = string(std::move(name), std::nullopt, std::move(description));
  k.format = "path";
  return k;
}

Key string_array(std::string name, std::string description) {
  return make(std::move(name), KeyType::string_array, "", std::move(description));
}

Key spectral(std::string name, double fallback, Range range, std::string unit,
             std::string description) {
  Key k = make(std::move(name), KeyType::spectral, std::move(unit), std::move(description));
  k.default_value = fallback;
  k.range = range;
  return k;
}

Key number_pair(std::string name, std::array<double, 2> fallback, Range range, std::string unit,
                std::string description) {
  Key k = make(std::move(name), KeyType::number_pair, std::move(unit), std::move(description));
  k.default_value = json::array({fallback[0], fallback[1]});
  k.range = range;
  return k;
}

Key number_tuple(std::string name, std::vector<std::pair<std::string, Range>> items,
                 std::string unit, std::string description) {
  Key k = make(std::move(name), KeyType::number_tuple, std::move(unit), std::move(description));
  k.items = std::move(items);
  return k;
}

Key object(std::string name, std::string description, std::vector<Key> children) {
  Key k = make(std::move(name), KeyType::object, "", std::move(description));
  k.nullable = true;  // null reads as an absent object: every key takes its default
  k.children = std::move(children);
  return k;
}

Key object_array(std::string name, json fallback, std::string description,
                 std::vector<Key> item_keys) {
  Key k = make(std::move(name), KeyType::object_array, "", std::move(description));
  k.default_value = std::move(fallback);
  k.children = std::move(item_keys);
  return k;
}

Key map(std::string name, std::string description, Key value) {
  Key k = make(std::move(name), KeyType::map, "", std::move(description));
  k.children = {std::move(value)};
  return k;
}

}  // namespace declare

// ---- keys declared with the member they set --------------------------------------------------

namespace {

// The keys of a settings struct S, each declared beside the member it sets (PDAL's args.add):
// its default is the member's initial value, and its reader sets the member. A member of a base
// of S is one of S.
template <typename S>
class Fields {
 public:
  // `key`, reading into `member` what read(reader, name) returns.
  template <typename M, typename C, typename Read>
  Key bind(Key key, M C::*member, Read read) const {
    static_assert(std::is_base_of_v<C, S>);
    M S::*target = member;
    key.owner = &typeid(S);
    key.read = [target, read, name = key.name](JsonReader& r, void* settings) {
      static_cast<S*>(settings)->*target = read(r, name);
    };
    return key;
  }

  Key number(std::string name, double S::*member, Range range, std::string unit,
             std::string description) const {
    return bind(declare::number(std::move(name), initial_.*member, range, std::move(unit),
                                std::move(description)),
                member, [](JsonReader& r, const std::string& key) { return r.number(key); });
  }
  // A number without a default: unset when absent or null.
  Key number(std::string name, std::optional<double> S::*member, Range range, std::string unit,
             std::string description) const {
    return bind(declare::number(std::move(name), std::nullopt, range, std::move(unit),
                                std::move(description)),
                member,
                [](JsonReader& r, const std::string& key) { return r.optional_number(key); });
  }
  Key integer(std::string name, int S::*member, std::int64_t min, std::uint64_t max,
              std::string unit, std::string description) const {
    return bind(declare::integer(std::move(name), initial_.*member, min, max, std::move(unit),
                                 std::move(description)),
                member, [](JsonReader& r, const std::string& key) {
                  return static_cast<int>(r.integer(key));
                });
  }
  Key integer(std::string name, std::int64_t S::*member, std::int64_t min, std::uint64_t max,
              std::string unit, std::string description) const {
    return bind(declare::integer(std::move(name), initial_.*member, min, max, std::move(unit),
                                 std::move(description)),
                member, [](JsonReader& r, const std::string& key) { return r.integer(key); });
  }
  Key boolean(std::string name, bool S::*member, std::string description) const {
    return bind(declare::boolean(std::move(name), initial_.*member, std::move(description)), member,
                [](JsonReader& r, const std::string& key) { return r.boolean(key); });
  }
  // A switch whose default depends on other keys (`default_text` says how): unset when absent.
  Key boolean(std::string name, std::optional<bool> S::*member, std::string description,
              std::string default_text) const {
    Key k = make(std::move(name), KeyType::boolean, "", std::move(description));
    k.default_text = std::move(default_text);
    return bind(std::move(k), member, [](JsonReader& r, const std::string& key) {
      return r.has(key) ? std::optional<bool>(r.boolean(key)) : std::nullopt;
    });
  }
  // One of `names`, the member holding the name.
  Key choice(std::string name, std::string S::*member, std::vector<std::string> names,
             std::string description) const {
    std::vector<std::pair<std::string, std::string>> values;
    for (const std::string& n : names) values.emplace_back(n, n);
    return choice_of(std::move(name), member, std::move(values), std::move(description));
  }
  // One of the names of `values`, the member holding the value of the name.
  template <typename T>
  Key choice_of(std::string name, T S::*member, std::vector<std::pair<std::string, T>> values,
                std::string description) const {
    std::vector<std::string> names;
    std::optional<std::string> fallback;
    for (const auto& [n, value] : values) {
      names.push_back(n);
      if (!fallback && value == initial_.*member) fallback = n;
    }
    return bind(
        declare::choice(std::move(name), fallback, std::move(names), std::move(description)),
        member,
        [values](JsonReader& r, const std::string& key) { return r.choice<T>(key, values); });
  }
  // A file's path: empty when absent, refused when given empty.
  Key path(std::string name, std::string S::*member, std::string description) const {
    return bind(declare::path(std::move(name), std::move(description)), member,
                [](JsonReader& r, const std::string& key) {
                  const std::optional<std::string> path = r.optional_string(key);
                  if (!path && r.declared(key, KeyType::string).required)
                    r.fail(key, "is required");
                  if (path && path->empty()) r.fail(key, "must not be empty");
                  return path.value_or("");
                });
  }
  // A string without a default: empty when absent or null.
  Key string(std::string name, std::string S::*member, std::string description) const {
    return bind(
        declare::string(std::move(name), std::nullopt, std::move(description)), member,
        [](JsonReader& r, const std::string& key) { return r.optional_string(key).value_or(""); });
  }
  // Non-empty strings; the member's initial value is the default when it holds any.
  Key string_array(std::string name, std::vector<std::string> S::*member,
                   std::string description) const {
    Key k = declare::string_array(std::move(name), std::move(description));
    if (!(initial_.*member).empty()) k.default_value = initial_.*member;
    return bind(std::move(k), member,
                [](JsonReader& r, const std::string& key) { return r.string_array(key); });
  }
  // An object read into a struct of its own, with the keys `children` declare for it.
  template <typename M>
  Key object(std::string name, M S::*member, std::string description,
             std::vector<Key> children) const {
    return bind(declare::object(std::move(name), std::move(description), std::move(children)),
                member, [](JsonReader& r, const std::string& key) {
                  M settings;
                  JsonReader o = r.object(key);
                  read_fields(o, {}, settings);
                  o.finish();
                  return settings;
                });
  }
  // The same, unset unless given.
  template <typename M>
  Key object(std::string name, std::optional<M> S::*member, std::string description,
             std::vector<Key> children) const {
    return bind(declare::object(std::move(name), std::move(description), std::move(children)),
                member, [](JsonReader& r, const std::string& key) -> std::optional<M> {
                  if (!r.has(key)) return std::nullopt;
                  M settings;
                  JsonReader o = r.object(key);
                  read_fields(o, {}, settings);
                  o.finish();
                  return settings;
                });
  }
  // An array of objects, each read into an M; absent: the member's initial value, which
  // `fallback` writes as JSON.
  template <typename M>
  Key object_array(std::string name, std::vector<M> S::*member, json fallback,
                   std::string description, std::vector<Key> item_keys) const {
    return bind(declare::object_array(std::move(name), std::move(fallback), std::move(description),
                                      std::move(item_keys)),
                member, [initial = initial_.*member](JsonReader& r, const std::string& key) {
                  std::vector<JsonReader> items = r.object_array(key);
                  if (items.empty()) {
                    r.resolved()[key] = r.declared(key, KeyType::object_array).default_value;
                    return initial;
                  }
                  std::vector<M> values(items.size());
                  for (std::size_t i = 0; i < items.size(); ++i) {
                    read_fields(items[i], {}, values[i]);
                    items[i].finish();
                  }
                  return values;
                });
  }

 private:
  const S initial_{};
};

}  // namespace

// ---- the declaration ------------------------------------------------------------------------

namespace {

using namespace declare;

constexpr double wgs84_equatorial_radius_m = 6378137.0;
constexpr std::uint64_t int_max = static_cast<std::uint64_t>(std::numeric_limits<int>::max());

std::vector<std::string> preset_names() {
  std::vector<std::string> names;
  for (const auto& [name, text] : sensor_presets()) names.push_back(name);
  return names;
}

Key sensor_keys() {
  const Fields<SensorSettings> s;
  using S = SensorSettings;
  Key preset = choice("preset", std::nullopt, preset_names(),
                      "`north2010` (the seed's Table 2, exactly), `glas` (the same with "
                      "GLAS's ~70 m beam), `gedi` (GEDI's power beam: 1064 nm, 15.6 ns FWHM, "
                      "~25 m from 420 km; set `track.altitude_m` to 420000) or `atlas` (ICESat-2's "
                      "strong beam: 532 nm, 1.5 ns FWHM, ~11 m from 496 km; set "
                      "`track.altitude_m` to 496000; docs/icesat2.md); keys beside it "
                      "override it (`bands` as a whole); absent: the values of `north2010`");
  preset.default_text = "none";
  return object(
      "sensor", "the lidar (the seed's Table 2)",
      {s.bind(std::move(preset), &S::preset,
              [](JsonReader& r, const std::string& key) {
                return r.optional_string(key).value_or("");
              }),
       // Up to 1 MHz: ATLAS fires 10 kHz, airborne scanners hundreds of kHz.
       s.number("pulse_rate_hz", &S::pulse_rate_hz, open_closed(0, 1e6), "Hz",
                "the laser's pulse rate (GLAS 40, GEDI 242, ATLAS 10 000): the shot rate of a "
                "track that gives no `rate_hz`, and so its shots' times and, without "
                "`spacing_m`, their spacing"),
       // 1 ps to 1 us: shorter would put the whole pulse energy into an infinite power; longer is
       // no longer a ranging pulse.
       s.number("pulse_sigma_ns", &S::pulse_sigma_ns, closed(0.001, 1000), "ns",
                "RMS width of the Gaussian pulse"),
       s.number("divergence_sigma_rad", &S::divergence_sigma_rad,
                open_closed(0, run_limits::angle_rad), "rad",
                "beam angular RMS width per axis (intensity ∝ exp(−θ²/2σ²))"),
       s.choice("beam_profile", &S::beam_profile, {"gaussian", "uniform"},
                "the beam's intensity across it: `gaussian` (∝ exp(−θ²/2σ²)) or `uniform` (the "
                "same over a cone of half-angle 2 `divergence_sigma_rad`: the same RMS per axis, "
                "its edge at the Gaussian's 1/e² contour; RAMI-IV's lidar footprint)"),
       s.number("ifov_rad", &S::ifov_rad, open_closed(0, run_limits::angle_rad), "rad",
                "detector full field of view (top-hat cone); the scene a shot builds grows with "
                "it (see Limits)"),
       // The largest telescopes built are about 80 m²; far beyond, received powers overflow.
       s.number("telescope_area_m2", &S::telescope_area_m2, open_closed(0, 100), "m²",
                "receiver aperture"),
       // 1 ps to 1 ms a bin: a window of bins beyond either end is no waveform.
       s.number("bin_ns", &S::bin_ns, closed(0.001, 1e6), "ns", "width of a recording bin"),
       s.integer("bins", &S::bins, 1, run_limits::waveform_bins, "",
                 "recording bins; the return from the footprint centre falls two thirds into the "
                 "window"),
       object_array("bands", json::parse(sensor_presets().at(default_sensor_preset))["bands"],
                    "the laser's bands: 532 and 1064 nm by default, with pulse energies of 32 and "
                    "72 mJ and round-trip transmissions of 0.8 and 0.9",
                    {string("name", std::nullopt,
                            "the band's name: the key of per-band values; unique, not empty")
                         .with_required(),
                     // Ultraviolet to far infrared: what a lidar through the atmosphere uses, and
                     // photon energies that stay finite.
                     number("wavelength_nm", std::nullopt, closed(100, 100000), "nm", "wavelength")
                         .with_required(),
                     // Spaceborne lasers fire tens of mJ, the largest research lasers a few kJ.
                     number("pulse_energy_mJ", std::nullopt, open_closed(0, 1e7), "mJ",
                            "energy of a transmitted pulse")
                         .with_required(),
                     number("atmos_transmission_roundtrip", std::nullopt, open_closed(0, 1), "",
                            "two-way transmission of the atmosphere; required without "
                            "`atmosphere`, refused beside it (its layers give it)")})
           .with_items(1, run_limits::bands)
           .with_default_text("the preset's"),
       s.choice("receiver", &S::receiver, {"waveform", "photon_counting"},
                "what the record is made of: `waveform` (the received waveform and its "
                "processing) or `photon_counting` (ICESat-2's photon events, written to "
                "`atl03.h5` and `atl08.h5`; docs/icesat2.md); the `atlas` preset's is "
                "`photon_counting`"),
       s.string_array("beams", &S::beams,
                      "photon counting: which of ATLAS's beams `gt1l gt1r gt2l gt2r gt3l gt3r` to "
                      "simulate (strong: the `l` beams backward, the `r` ones forward; weak: the "
                      "others, at 45/175 of the energy), each on its own ground track about the "
                      "`pass`'s reference track; several only on a `pass`"),
       s.choice("sc_orient", &S::sc_orient, {"backward", "forward"},
                "photon counting: the spacecraft's orientation (ATL03's `orbit_info/sc_orient` "
                "0 or 1): `backward` makes the `l` beam of each pair strong and `gt1l` ... "
                "`gt3r` ATLAS's spots 1 ... 6, `forward` the `r` beams strong and the spots 6 "
                "... 1"),
       s.number("photon_efficiency", &S::photon_efficiency, open_closed(0, 1), "",
                "photon counting: the receiver's optical throughput times its detectors' photon "
                "detection efficiency (ATLAS: 0.45 × 0.15)"),
       s.number("filter_bandwidth_nm", &S::filter_bandwidth_nm, above(0), "nm",
                "photon counting: the receiver filter's equivalent width (the solar background "
                "grows with it)"),
       s.number("dead_time_ns", &S::dead_time_ns, at_least(0), "ns",
                "photon counting: each detector channel's non-paralysable dead time (16 channels "
                "a strong beam, 4 a weak one)")});
}

Key atmosphere_keys() {
  const Fields<AtmosphereLayer> l;
  using L = AtmosphereLayer;
  // Heights: the shore of the Dead Sea lies 430 m below the ellipsoid; the atmosphere ends near
  // 100 km.
  const Range heights = closed(-1000, 100000);
  const auto height = [&](const char* name, double L::*member, const char* description) {
    return l.bind(number(name, std::nullopt, heights, "m", description).with_required(), member,
                  [](JsonReader& r, const std::string& key) { return r.number(key); });
  };
  Key phase = make("phase", KeyType::choice_or_object, "",
                   "the layer's phase function: `rayleigh` (molecules), `{\"hg_g\": g}` "
                   "(Henyey–Greenstein of asymmetry g) or `{\"hg2\": [g1, g2, w]}` (w HG(g1) + "
                   "(1 − w) HG(g2), a forward and a backward peak)");
  phase.choices = {"rayleigh"};
  phase.required = true;
  phase.children = {
      number("hg_g", std::nullopt, open(-1, 1), "", "Henyey–Greenstein asymmetry g"),
      number_tuple("hg2", {{"g1", open(-1, 1)}, {"g2", open(-1, 1)}, {"w", closed(0, 1)}}, "",
                   "two-term Henyey–Greenstein: the asymmetries of its two terms and the weight "
                   "of the first")};
  Key atmosphere =
      make("atmosphere", KeyType::choice_or_object, "",
           "the atmosphere's layers on the light's path (docs/physics.md): a preset's name, or "
           "an object. With it, each band's two-way transmission comes from the layers (give "
           "no `sensor.bands[].atmos_transmission_roundtrip` beside it); absent: each band's "
           "fixed `atmos_transmission_roundtrip`, as before");
  atmosphere.default_text = "none";
  atmosphere.choices = atmosphere_preset_names();
  Key preset =
      choice("preset", std::nullopt, atmosphere_preset_names(),
             "`clear` (molecules and a clean continental aerosol, τ 0.064 at 550 nm), "
             "`haze` (molecules and a polluted one, τ 0.327), `cirrus` (`clear` and a "
             "cirrus of τ 0.3 at 9–11 km above the ellipsoid) or `stratus` (`clear` "
             "and a stratus of τ 2 at 0.5–1.5 km above the ground), expanded for the "
             "bands' wavelengths (docs/guide/atmosphere.md); `layers` beside it replace its own");
  preset.default_text = "none";
  // Beyond an optical depth of 50 the two-way transmission is below 1e-43.
  Key optical_depth = spectral("optical_depth", 0.0, closed(0, 50), "",
                               "the layer's vertical extinction optical depth");
  optical_depth.default_value = nullptr;
  optical_depth.required = true;
  atmosphere.children = {
      std::move(preset),
      object_array(
          "layers", nullptr,
          "horizontally uniform layers, which may overlap; the preset's when not given",
          {height("base_m", &L::base_m, "the layer's base"),
           height("top_m", &L::top_m, "the layer's top, above its base"),
           l.choice_of("above", &L::above_ellipsoid, {{"ground", false}, {"ellipsoid", true}},
                       "what the heights are measured from: the ground under the footprint "
                       "centre, or the WGS84 ellipsoid"),
           std::move(optical_depth),
           spectral("single_scattering_albedo", 1.0, closed(0, 1), "",
                    "the part of the extinction that scatters"),
           std::move(phase)})
          .with_items(1, std::numeric_limits<std::size_t>::max())
          .with_default_text("the preset's")};
  return atmosphere;
}

Key background_key() {
  Key background = make("background", KeyType::choice_or_object, "",
                        "photon counting's background light: `sun` (the sun at each shot's time "
                        "and place over a Lambertian scene of the shot's reflectance), `none`, or "
                        "`{\"rate_MHz\": R}` detected photons a microsecond");
  background.default_value = "sun";
  background.choices = {"sun", "none"};
  background.children = {number("rate_MHz", std::nullopt, at_least(0), "MHz",
                                "background photons detected a "
                                "microsecond")
                             .with_required()};
  return background;
}

Key simulation_keys() {
  const Fields<SimulationSettings> s;
  using S = SimulationSettings;
  return object(
      "simulation", "the Monte Carlo transport",
      {s.integer("rays_per_shot", &S::rays_per_shot, 1, run_limits::rays_per_shot, "",
                 "Monte Carlo rays a shot (error falls as n^−1/2)"),
       s.integer("max_order", &S::max_order, 1, run_limits::max_order, "",
                 "highest scattering order"),
       s.choice_of("sampling", &S::quasi_random, {{"random", false}, {"sobol", true}},
                   "how rays draw their beam direction and first free path: `random` "
                   "(plain Monte Carlo) or `sobol` (the shot's scrambled Sobol' points: "
                   "unbiased; on the seed's base case the mean waveform's error at 10^4 "
                   "rays is that of 1.9× the rays at the same cost; the noise the processing "
                   "weighs its fits with, computed for independent rays, is then overstated)"),
       background_key()});
}

Key terrain_keys() {
  const TerrainSettings t;
  const Fields<TerrainSettings> f;
  const Fields<PlaneSettings> p;
  const Fields<RoughnessSettings> g;
  Key dem =
      path("dem",
           "a raster GDAL reads, with a CRS (geographic or projected; nodata honoured); "
           "exactly one of `dem`, `plane` and `point_cloud`. A shot whose beam (3 σ) falls over "
           "nodata or "
           "off the raster is flagged, its waveform fill. An unusable file (missing, corrupt, "
           "truncated, no CRS) is an error, exit status 3");
  Key dem_band = integer("dem_band", std::nullopt, 1, int_max, "",
                         "`dem` only: the band of heights (from 1); required when the raster has "
                         "more than one");
  Key datum = choice(
      "vertical_datum", t.vertical_datum, {"ellipsoid", "egm96"},
      "`dem` and `point_cloud` only: what the DEM's (the cloud's) heights are measured from when "
      "its CRS has no vertical part: "
      "`ellipsoid` (its own), `egm96` (the EGM96 geoid, through PROJ's `egm96_15.gtx`), or a "
      "vertical CRS PROJ knows (`EPSG:3855` when its grid is installed). A DEM with a vertical "
      "CRS of its own uses it when this key is not set; set to another datum, it is refused. The "
      "choice made is in the run summary and in the products' `config`");
  datum.open_choices = true;
  datum.what_else = "a vertical CRS as AUTHORITY:CODE";
  datum.pattern = ":";
  Key terrain =
      object(
          "terrain", "the ground: exactly one of `dem`, `plane` and `point_cloud`",
          {std::move(dem),
           f.object("plane", &TerrainSettings::plane,
                    "a synthetic plane, anchored at the origin's latitude and longitude, for slope "
                    "studies; exactly one of `dem`, `plane` and `point_cloud`",
                    {p.number("origin_lat_deg", &PlaneSettings::origin_lat_deg, closed(-90, 90),
                              "deg", "latitude of the origin"),
                     p.number("origin_lon_deg", &PlaneSettings::origin_lon_deg, closed(-180, 360),
                              "deg", "longitude of the origin"),
                     p.number("elevation_m", &PlaneSettings::elevation_m, closed(-1e5, 1e5), "m",
                              "height of the origin above WGS84"),
                     p.number("slope_deg", &PlaneSettings::slope_deg, closed(0, 89), "deg",
                              "slope of the plane"),
                     p.number("aspect_deg", &PlaneSettings::aspect_deg, any_finite(), "deg",
                              "the azimuth the slope faces (clockwise from north)")}),
           f.boolean("point_cloud", &TerrainSettings::point_cloud,
                     "`true`: the ground of `canopy.point_cloud`'s cloud (its class-2 points "
                     "gridded on its voxels' columns, as `glaswave voxelize` writes "
                     "`ground_elevation`), without a DEM file; exactly one of `dem`, `plane` and "
                     "`point_cloud`, and only with a `canopy.point_cloud`; `false` is refused "
                     "(give `dem` or `plane` instead)",
                     "absent")
               .with_only(true),
           std::move(dem_band), std::move(datum),
           f.object(
               "roughness", &TerrainSettings::roughness,
               "random relief added under the beam (a Gaussian random field with covariance "
               "exp(−r²/L²), fixed by position and `seed`, meshed every L/3, or L/2 or L where the "
               "field of view needs more than 1024 nodes a side, else refused)",
               {g.number("rms_m", &RoughnessSettings::rms_m, at_least(0), "m",
                         "RMS height of the relief"),
                g.number("correlation_m", &RoughnessSettings::correlation_m, above(0), "m",
                         "correlation length L")}),
           spectral("soil_reflectance", 0.15, closed(0, 1), "", "Lambertian soil, per band")})
          .with_required();
  return terrain;
}

Key canopy_keys() {
  const CanopySettings c;
  const Fields<CanopySettings> f;
  using S = CanopySettings;
  Key lad = make("lad", KeyType::choice_or_object, "",
                 "leaf angle distribution: a name, or `{\"ellipsoidal_mean_deg\": X}` for "
                 "Campbell's ellipsoidal distribution");
  lad.default_value = "spherical";
  lad.choices = {"spherical",   "planophile",   "erectophile",
                 "plagiophile", "extremophile", "uniform"};
  lad.children = {number("ellipsoidal_mean_deg", std::nullopt, open(0, 90), "deg",
                         "mean leaf inclination of the ellipsoidal distribution")
                      .with_required()};
  // canopy.voxels and canopy.point_cloud: measured vegetation instead of crowns (PRODUCT.md
  // section 8); their leaves' keys are the canopy's, with the defaults of a grid of leaves.
  const auto leaves = [&] {
    return std::vector<Key>{Key(lad),
                            f.number("leaf_size_m", &S::leaf_size_m, at_least(0), "m",
                                     "the hotspot's correlation length; 0 is the point-leaf limit"),
                            spectral("leaf_reflectance", 0.4, closed(0, 1), "", "per band"),
                            spectral("leaf_transmittance", 0.4, closed(0, 1), "",
                                     "per band; `leaf_reflectance` + `leaf_transmittance` ≤ 1"),
                            f.number("bark_fraction", &S::bark_fraction, closed(0, 1), "",
                                     "the bark's part of the plant area (opaque, Lambertian)")
                                .with_default(0.0),
                            spectral("bark_reflectance", 0.3, closed(0, 1), "", "per band")};
  };
  std::vector<Key> voxel_keys = leaves();
  voxel_keys.insert(voxel_keys.begin(),
                    f.path("file", &S::voxels_file,
                           "plant area density (m²/m³) on a regular grid: a CF NetCDF variable "
                           "`pad(z, y, x)` with a CRS, z the height above the ground; or a "
                           "multi-band GeoTIFF, band i the slice between its metadata `z_bottom_m` "
                           "and `z_top_m`")
                        .with_required());
  std::vector<Key> cloud_keys = leaves();
  cloud_keys.insert(
      cloud_keys.begin(),
      {f.path("file", &S::point_cloud_file,
              "an airborne lidar point cloud, LAS 1.0–1.4 uncompressed (LAZ: decompress it with "
              "`laszip` or `pdal translate`), voxelised at start by gap-fraction inversion as "
              "`glaswave voxelize` does")
           .with_required(),
       f.string("crs", &S::point_cloud_crs,
                "the cloud's CRS when the file has no WKT or GeoTIFF-keys record (`EPSG:32633`, "
                "WKT, PROJ)"),
       f.number("voxel_size_m", &S::voxel_size_m, closed(0.05, 100), "m",
                "the voxels' width and depth")});
  Key canopy = object(
      "canopy",
      "the vegetation (names of the seed's Table 1): bare ground when null or absent; `{}` is "
      "Table 1. Leaves are bi-Lambertian, bark and soil Lambertian. Trees stand on the local "
      "ground; the same tree is in the same place for every shot that sees it",
      {f.number("pai", &S::pai, at_least(0), "m²/m²",
                "one-sided plant area of leaves and bark per unit ground area of the scene (with "
                "`crowns_file`: of the crowns' bounding box)"),
       std::move(lad),
       f.number("cover", &S::cover, closed(0, 1), "",
                "crown cover, crowns placed at random (below 1 unless `crown_shape` is `layer`)"),
       number("green_fraction", c.green_fraction, closed(0, 1), "",
              "the leaves' part of the plant area; 1 − `bark_fraction` when only that is given"),
       number("bark_fraction", c.bark_fraction, closed(0, 1), "",
              "the bark's part of the plant area; 1 − `green_fraction` when only that is given; "
              "the two add up to 1"),
       f.choice_of(
           "crown_shape", &S::crown_shape,
           {{"ellipsoid", CrownShape::ellipsoid},
            {"cone", CrownShape::cone},
            {"layer", CrownShape::layer}},
           "`ellipsoid`, `cone`, or `layer`: a homogeneous slab over the whole scene, "
           "`crown_base_m[0]` to `crown_base_m[0] + 2 crown_half_height_m` above the ground "
           "(`pai` is its total)"),
       // No tree is wider or taller than 100 m; a crown of 1e6 m made the stand lookup run for
       // minutes.
       f.number("crown_radius_m", &S::crown_radius_m, open_closed(0, 100), "m", "crown radius"),
       f.number("crown_half_height_m", &S::crown_half_height_m, open_closed(0, 100), "m",
                "crown half height"),
       number_pair(
           "crown_base_m", c.crown_base_m, at_least(0), "m",
           "[min, max]: crown bases uniform in this range above the terrain under the stem"),
       f.number("leaf_size_m", &S::leaf_size_m, at_least(0), "m",
                "the hotspot's correlation length; 0 is the point-leaf limit"),
       f.number("dbh_m", &S::dbh_m, at_least(0), "m",
                "trunk diameter; trunks from the ground to the crown"),
       spectral("leaf_reflectance", 0.4, closed(0, 1), "", "per band"),
       spectral("leaf_transmittance", 0.4, closed(0, 1), "",
                "per band; `leaf_reflectance` + `leaf_transmittance` ≤ 1"),
       spectral("bark_reflectance", 0.3, closed(0, 1), "", "per band"),
       f.path("crowns_file", &S::crowns_file,
              "a CSV of explicit crowns instead of random ones: header "
              "`lon,lat,base_m,radius_m,half_height_m` (degrees) or "
              "`x,y,base_m,radius_m,half_height_m` (metres east and north of `terrain.plane`'s "
              "origin); `pai` is then per unit area of the crowns' bounding box"),
       f.path("stands", &S::stands,
              "a vector file GDAL/OGR reads (GeoJSON, GeoPackage, Shapefile, FlatGeobuf...) of "
              "Polygons or MultiPolygons, every layer's features, whose attribute fields (GeoJSON "
              "`properties`) override canopy keys inside them (`{\"pai\": 1.5, \"lad\": "
              "\"erectophile\"}`; a text field holding a JSON object or array is read as that "
              "JSON); in any CRS, brought to WGS84 with PROJ: a layer without one is taken as "
              "longitude and latitude, and is an error if its coordinates are not; checked like "
              "the configuration, a bad file is exit status 3 naming the feature and key; not with "
              "a `layer`"),
       object("voxels",
              "a voxel grid of plant area density instead of crowns (no other canopy key "
              "beside it): each voxel a turbid cell of these leaves, each column standing on "
              "the terrain under its centre",
              std::move(voxel_keys)),
       object("point_cloud",
              "an airborne lidar point cloud instead of crowns (no other canopy key beside it): "
              "ground points (class 2) and the other returns voxelised by gap-fraction "
              "inversion, each voxel a turbid cell of these leaves",
              std::move(cloud_keys)),
       object(
           "facets",
           "facet trees instead of crowns (no other canopy key beside it): triangle meshes or "
           "disc leaves, one shared model each, placed by `trees_file`, each tree standing on "
           "the terrain under its stem (or floating `z_m` above it)",
           {f.path(
                 "trees_file", &S::facet_trees_file,
                 "the trees: a `.csv` with header `lon,lat,model,rotation_deg,scale` (degrees) or "
                 "`x,y,model,rotation_deg,scale` (metres east and north of `terrain.plane`'s "
                 "origin), either with a last column `z_m` (the model's origin above the ground, "
                 "0 to 1000 m; 0 when absent), or any vector file OGR reads of points (in any "
                 "CRS) with the attributes `model`, `rotation_deg` and `scale` (and optionally "
                 "`z_m`); `rotation_deg` turns the model's +y axis to that azimuth (clockwise "
                 "from north)")
                .with_required(),
            map("models",
                "each model's name and its file: a mesh (any format Assimp reads: OBJ, PLY, "
                "glTF, ...; metres, z up, the stem's foot at the origin), or leaves as discs in "
                "RAMI's text, a `*.def` file of one disc a line `radius x y z nx ny nz` (metres, "
                "the model's frame), all of `disc_material`",
                path("NAME", "the mesh or disc leaf file"))
                .with_required(),
            f.bind(declare::string("disc_material", std::nullopt,
                                   "the material (an entry of `materials`, two-sided when it "
                                   "has a `transmittance`) of every disc of the disc leaf "
                                   "models")
                       .with_default_text("`leaf`"),
                   &S::facet_disc_material,
                   [](JsonReader& r, const std::string& key) {
                     return r.optional_string(key).value_or("leaf");
                   }),
            map("materials",
                "the optics of each material name the meshes use (a mesh material without an "
                "entry is an error)",
                object("NAME",
                       "a leaf when `transmittance` is given (two-sided bi-Lambertian), else "
                       "opaque and Lambertian (wood)",
                       {spectral("reflectance", 0.0, closed(0, 1), "", "per band").with_required(),
                        spectral("transmittance", 0.0, closed(0, 1), "",
                                 "per band; given: a two-sided leaf, `reflectance` + "
                                 "`transmittance` ≤ 1")
                            .with_default_text("none: opaque")}))
                .with_required()})});
  canopy.default_text = "null";
  return canopy;
}

Key track_keys() {
  const Fields<TrackSettings> t;
  const Fields<OrbitElements> o;
  using S = TrackSettings;
  using O = OrbitElements;
  return object(
      "track", "the shots: where they are and how the beam points",
      {t.choice_of("type", &S::type,
                   {{"pass", TrackType::pass},
                    {"points", TrackType::points},
                    {"orbit", TrackType::orbit},
                    {"ephemeris", TrackType::ephemeris},
                    {"granule", TrackType::granule}},
                   "how shots are placed: `pass`, `points`, `orbit`, `ephemeris` or `granule`"),
       t.number("start_lat_deg", &S::start_lat_deg, closed(-90, 90), "deg",
                "`pass`: the spacecraft flies the geodesic from here along the heading"),
       t.number("start_lon_deg", &S::start_lon_deg, closed(-180, 360), "deg",
                "`pass`: see `start_lat_deg`"),
       t.number("heading_deg", &S::heading_deg, any_finite(), "deg",
                "`pass`: the heading, clockwise from north"),
       t.integer("shots", &S::shots, 1, run_limits::track_shots, "",
                 "shots of a pass. `orbit`: shots at `rate_hz` from `start_time`, numbered by "
                 "their place in that sequence; only those whose footprint falls on the terrain "
                 "are simulated and written, the others skipped (`check` says how many). "
                 "`points`: the number of points"),
       t.number("rate_hz", &S::rate_hz, above(0), "Hz", "shot rate (times)")
           .with_default_text("`sensor.pulse_rate_hz`"),
       t.number("spacing_m", &S::spacing_m, above(0), "m",
                "spacing of shots along track; from the orbital ground speed and `rate_hz` when "
                "not given")
           .with_default_text("from speed"),
       t.number("altitude_m", &S::altitude_m, open_closed(0, run_limits::altitude_m), "m",
                "spacecraft height above WGS84 (`pass`, `points`, `granule`)"),
       time("start_time", "2000-01-01T12:00:00Z", "ISO 8601 UTC time of shot 0"),
       t.number("off_nadir_deg", &S::off_nadir_deg, half_open(0, 45), "deg",
                "beam tilted from geodetic nadir, for every type; a track none of whose shots "
                "meets the terrain is an error (exit status 3)"),
       t.number("pointing_azimuth_deg", &S::pointing_azimuth_deg, any_finite(), "deg",
                "the azimuth the beam is tilted toward (clockwise from north)"),
       object_array(
           "points", json(), "`points`: targets on the ground, one shot each",
           {number("lat_deg", std::nullopt, closed(-90, 90), "deg", "latitude").with_required(),
            number("lon_deg", std::nullopt, closed(-180, 360), "deg", "longitude").with_required()})
           .with_items(1, run_limits::track_shots),
       o.number("semi_major_axis_m", &O::semi_major_axis_m,
                open_closed(wgs84_equatorial_radius_m,
                            wgs84_equatorial_radius_m + run_limits::altitude_m),
                "m",
                "`orbit`: mean elements at `epoch` in the true-equator mean-equinox frame (as "
                "two-line elements), propagated with the J2 secular drift of node, perigee and "
                "mean anomaly, turned Earth-fixed with GMST (UT1 taken as UTC)"),
       o.number("eccentricity", &O::eccentricity, half_open(0, 1), "",
                "`orbit`: the perigee must be above the Earth"),
       o.number("inclination_deg", &O::inclination_deg, closed(0, 180), "deg", "`orbit`"),
       o.number("raan_deg", &O::raan_deg, any_finite(), "deg",
                "`orbit`: right ascension of the ascending node"),
       o.number("arg_perigee_deg", &O::arg_perigee_deg, any_finite(), "deg",
                "`orbit`: argument of perigee"),
       o.number("mean_anomaly_deg", &O::mean_anomaly_deg, any_finite(), "deg", "`orbit`"),
       time("epoch", std::nullopt, "`orbit`: ISO 8601 UTC time of the elements")
           .with_default_text("`start_time`"),
       t.path("ephemeris", &S::ephemeris,
              "`ephemeris`: a CSV file, one shot a row, with a header row "
              "`time,x_m,y_m,z_m[,pointing_x,pointing_y,pointing_z]` (any order): time as ISO "
              "8601 UTC or seconds since 2000-01-01T12:00:00Z, the spacecraft's WGS84 Earth-fixed "
              "position (m), and optionally the beam direction (Earth-fixed, any length); without "
              "it the beam points by `off_nadir_deg` and `pointing_azimuth_deg`. Lines starting "
              "with `#` are skipped; errors name `file:line`"),
       t.path("file", &S::granule,
              "`granule`: a GEDI L2A granule (groups `BEAM0000` to `BEAM1011`, GEDI's eight "
              "beams, with `shot_number`, `lat_lowestmode`, `lon_lowestmode`, `delta_time`) or a "
              "GLAS GLAH14 granule (`Data_40HZ` with `Geolocation/d_lat`, `d_lon`, "
              "`Time/d_UTCTime_40`, `i_rec_ndx`, `i_shot_count`: all required), "
              "HDF5: one shot per footprint, aimed at its latitude and longitude from `altitude_m` "
              "as a point is, at its time, its `shot_number` the granule's (GLAH14: `i_rec_ndx` * "
              "40 + the shot in its record); footprints whose position is a fill value are "
              "skipped"),
       t.string_array("beams", &S::beams,
                      "`granule`: the beams to take, by group name (`[\"BEAM0101\"]`; GLAH14's one "
                      "is `Data_40HZ`); a beam not in the file is exit status 3")
           .with_default_text("all")});
}

// `section` with the switches parts declare in it (core/part_switch.hpp) after its own keys;
// its reader reads them into its settings' `switches`.
Key with_part_switches(Key section) {
  for (const auto& entry : Registry<PartSwitch>::instance().entries())
    if (entry.make.section == section.name)
      section.children.push_back(
          declare::boolean(entry.name, entry.make.fallback, entry.make.description));
  return section;
}

Key output_keys() {
  const Fields<OutputSettings> o;
  const Fields<RamiLidarSettings> r;
  using S = OutputSettings;
  const std::string photon_counting = "true with `sensor.receiver: photon_counting`, else false";
  return object(
      "output", "which products to write; at least one of `netcdf`, `footprints` and a granule",
      {o.boolean("netcdf", &S::netcdf, "write `shots.nc`"),
       o.boolean("footprints", &S::footprints,
                 "write the footprints' layer (`footprints.geojson`, or `footprints.gpkg` as "
                 "`footprints_format` says)"),
       declare::boolean("geojson", true,
                        "the old name of `footprints`: it still works, with a warning; not beside "
                        "`footprints`")
           .with_default(nullptr)
           .with_default_text("`footprints`"),
       o.boolean("plots", &S::plots,
                 "PNG plots (drawn from both products: needs `netcdf` and `footprints`)"),
       o.boolean("per_order", &S::per_order, "per-scattering-order waveforms"),
       o.boolean("metrics", &S::metrics,
                 "the waveform metrics and Gaussian decomposition (`energy_tr` ... `rh`); "
                 "false skips them, leaving them fill (`n_peaks` 0): shots are then not "
                 "flagged no or low signal, a detected waveform's `reflectance` is fill, "
                 "and `plots` is refused"),
       o.choice("footprints_format", &S::footprints_format, {"GeoJSON", "GPKG"},
                "the footprints' format: `footprints.geojson`, or `footprints.gpkg` "
                "(GeoPackage)"),
       o.boolean("glah01", &S::glah01,
                 "write `glah01.h5`, a GLAS GLAH01-style granule (waveforms)"),
       o.boolean("glah14", &S::glah14,
                 "write `glah14.h5`, a GLAS GLAH14-style granule (elevations, Gaussians)"),
       o.choice("glas_ellipsoid", &S::glas_ellipsoid, {"wgs84", "topex"},
                "the GLAS granules' heights: on WGS84, or on GLAS's TOPEX/Poseidon "
                "ellipsoid (`Geophysical/d_deltaEllip` is WGS84 less T/P height)"),
       o.boolean("atl03", &S::atl03, "the ATL03-like photons `atl03.h5` (photon counting)",
                 photon_counting),
       o.boolean("atl08", &S::atl08, "the ATL08-like land segments `atl08.h5` (photon counting)",
                 photon_counting),
       o.object(
           "rami", &S::rami,
           "RAMI-IV's lidar measurements in ROMC's format, the return binned by height from the "
           "ground up, written to `DIR/rami/` (docs/guide/rami.md); absent: none",
           {r.bind(declare::string_array("measurements",
                                         "ROMC's measurement identifiers: `lidar_sgl_co` (light "
                                         "scattered once: needs `per_order`) and `lidar_tot` "
                                         "(all of it)")
                       .with_default(RamiLidarSettings{}.measurements),
                   &RamiLidarSettings::measurements,
                   // Absent: both (an empty list given is refused by the checks).
                   [](JsonReader& reader, const std::string& key) {
                     const bool given = reader.has(key);
                     std::vector<std::string> names = reader.string_array(key);
                     return given ? names : RamiLidarSettings{}.measurements;
                   }),
            r.string("experiment", &RamiLidarSettings::experiment,
                     "ROMC's experiment identifier; `{band}` is replaced by the band's name, as "
                     "it must be with more than one band")
                .with_required(),
            r.string("model", &RamiLidarSettings::model,
                     "ROMC's model identifier: 1 to 10 letters and digits")
                .with_default("glaswave"),
            r.number("height_bin_m", &RamiLidarSettings::height_bin_m, open_closed(0, 1000), "m",
                     "the files' height interval: a whole number of the window's bins "
                     "(c `bin_ns` / 2 each)")})});
}

Key detector_keys() {
  const Fields<DetectorSettings> d;
  using S = DetectorSettings;
  return object(
      "detector",
      "the receiver between the light and the recorded waveform, to make waveforms that look "
      "like GLAS's; off by default. Levels are in W at the detector's input and `rx_waveform` "
      "stays in W; its noise is keyed by (seed, shot, band, bin), the same for any threads or "
      "split. The truth parts `rx_waveform_canopy`/`_ground` stay noise-free",
      {d.boolean("enabled", &S::enabled, "whether the detector applies"),
       // Levels at the detector: returns are microwatts; a watt of light or noise is already far
       // beyond any detector, and larger levels overflow the products.
       d.number("background_W", &S::background_W, closed(0, 1), "W",
                "mean background light (a sunlit scene)"),
       d.boolean("photon_noise", &S::photon_noise,
                 "Poisson statistics of signal and background photons, hν from each band's "
                 "wavelength"),
       d.number("quantum_efficiency", &S::quantum_efficiency, open_closed(0, 1), "",
                "photoelectrons per photon, for `photon_noise`"),
       d.number("noise_rms_W", &S::noise_rms_W, closed(0, 1), "W", "Gaussian detector noise, RMS"),
       // Photomultipliers reach 1e8; 1e12 leaves the products finite.
       d.number("gain", &S::gain, open_closed(0, 1e12), "", "amplification before the digitiser"),
       d.integer("bits", &S::bits, 0, 32, "", "digitiser resolution; 0: not digitised"),
       d.number("saturation_W", &S::saturation_W, open_closed(0, 1e12), "W",
                "the digitiser's full scale after the gain; required with `bits`; output above it "
                "clips, below 0 reads 0")
           .with_default_text("none")});
}

Key brf_keys() {
  const Fields<BrfSettings> b;
  const Fields<BrfView> v;
  const Fields<BrfRamiSettings> r;
  const BrfView view;
  using S = BrfSettings;
  return object(
      "brf", "`glaswave brf` (FLIGHT's solar mode)",
      {b.number("sun_zenith_deg", &S::sun_zenith_deg, half_open(0, 90), "deg", "sun zenith angle"),
       b.number("sun_azimuth_deg", &S::sun_azimuth_deg, any_finite(), "deg", "sun azimuth"),
       b.object_array(
            "views", &S::views,
            json::array({{{"zenith_deg", view.zenith_deg}, {"azimuth_deg", view.azimuth_deg}}}),
            "the view directions of the reflectance",
            {v.number("zenith_deg", &BrfView::zenith_deg, half_open(0, 90), "deg",
                      "view zenith angle"),
             v.number("azimuth_deg", &BrfView::azimuth_deg, any_finite(), "deg", "view azimuth")})
           .with_items(1, std::numeric_limits<std::size_t>::max()),
       b.integer("photons", &S::photons, 1, run_limits::rays_per_shot, "",
                 "photons traced from the sun"),
       b.number("image_resolution_m", &S::image_resolution_m, above(0), "m",
                "pixel size of `scene.tif`"),
       b.number("scene_size_m", &S::scene_size_m, open_closed(0, run_limits::brf_scene_m), "m",
                "side of the square scene around the track's first footprint that the sun "
                "lights (periodic over a synthetic plane); rounded up to whole pixels, at most "
                "8192 of them (see Limits)"),
       b.object("rami", &S::rami,
                "RAMI's measurements in ROMC's format, written to `DIR/rami/` beside `brf.json` "
                "(docs/guide/rami.md); absent: none",
                {r.string_array("measurements", &BrfRamiSettings::measurements,
                                "ROMC's measurement identifiers: `brfpp`, `brfop` (76 view "
                                "zeniths from -75 to 75 deg in the principal and orthogonal "
                                "planes), their parts `brfpp_co_sgl`, `brfpp_uc_sgl`, "
                                "`brfpp_mlt` (and `brfop_`'s), `brf1` (the albedo), `fabs`, "
                                "`ftran`, `falb`"),
                 r.string("experiment", &BrfRamiSettings::experiment,
                          "ROMC's experiment identifier (`HET01_DIS_UNI_NIR_20`); `{band}` is "
                          "replaced by the band's name, as it must be with more than one band")
                     .with_required(),
                 r.string("model", &BrfRamiSettings::model,
                          "ROMC's model identifier: 1 to 10 letters and digits")
                     .with_default("glaswave")})});
}

Key table_keys() {
  const Fields<TableSettings> t;
  using S = TableSettings;
  return object(
      "table",
      "`glaswave table`: the forward table of the `rt` retrieval (docs/retrieval.md); ignored "
      "by `run`",
      {map("vary",
           "keys (dotted paths, as `--set` names them) and the range [low, high] each is sampled "
           "over by a seeded low-discrepancy (Halton) design",
           number_pair("NAME", {0.0, 1.0}, any_finite(), "", "the key's range")),
       map("values",
           "keys and the values each takes, chosen evenly by the design (each read as `--set` "
           "reads VALUE: JSON when it parses, else a string)",
           string_array("NAME", "the key's values")),
       t.integer("entries", &S::entries, 1, 1000000, "", "entries of the table"),
       t.integer("shots_per_entry", &S::shots_per_entry, 1, 64, "",
                 "the track's first shots simulated for each entry: their mean is its waveform, "
                 "their scatter the table's Monte Carlo noise (at least 2 to measure it)")});
}

}  // namespace

const Key& configuration_keys() {
  static const Key root = [] {
    const Config c;
    Key schema =
        declare::string("$schema", std::nullopt,
                        "the JSON Schema an editor checks the file against (`glaswave check "
                        "--schema`); not a setting");
    schema.default_text = "none";
    return declare::object(
        "", "a glaswave configuration",
        {std::move(schema),
         declare::integer("seed", static_cast<std::int64_t>(c.seed), 0,
                          std::numeric_limits<std::uint64_t>::max(), "",
                          "random seed: a shot's waveform depends only on the configuration, the "
                          "seed and its shot number"),
         sensor_keys(), atmosphere_keys(), simulation_keys(), terrain_keys(), canopy_keys(),
         track_keys(), with_part_switches(output_keys()), detector_keys(), brf_keys(),
         table_keys()});
  }();
  return root;
}

// ---- the JSON Schema ------------------------------------------------------------------------

namespace {

std::string schema_description(const Key& k) {
  std::string text = k.description;
  if (!k.unit.empty()) text += " (unit: " + k.unit + ")";
  if (k.default_value.is_null() && !k.default_text.empty() && k.default_text != "none")
    text += " (default: " + k.default_text + ")";
  return text;
}

void add_range(json& s, const Range& r) {
  if (r.low) s[r.low_open ? "exclusiveMinimum" : "minimum"] = *r.low;
  if (r.high) s[r.high_open ? "exclusiveMaximum" : "maximum"] = *r.high;
}

json object_schema(const Key& k);

json key_schema(const Key& k) {
  json s = json::object();
  switch (k.type) {
    case KeyType::number:
      s["type"] = "number";
      add_range(s, k.range);
      break;
    case KeyType::integer:
      s["type"] = "integer";
      s["minimum"] = k.min;
      s["maximum"] = k.max;
      break;
    case KeyType::boolean:
      s["type"] = "boolean";
      break;
    case KeyType::string:
      s["type"] = "string";
      if (k.format == "date-time") s["format"] = "date-time";
      if (k.format == "path") s["minLength"] = 1;
      if (!k.choices.empty() && !k.open_choices) s["enum"] = k.choices;
      if (!k.choices.empty() && k.open_choices) {
        s["anyOf"] = json::array({{{"enum", k.choices}}, {{"pattern", k.pattern}}});
      }
      break;
    case KeyType::spectral: {
      json per_band = {{"type", "number"}};
      add_range(per_band, k.range);
      s["anyOf"] = json::array(
          {per_band,
           {{"type", "object"}, {"minProperties", 1}, {"additionalProperties", per_band}}});
      break;
    }
    case KeyType::number_pair: {
      json item = {{"type", "number"}};
      add_range(item, k.range);
      s = {{"type", "array"}, {"items", item}, {"minItems", 2}, {"maxItems", 2}};
      break;
    }
    case KeyType::number_tuple: {
      json items = json::array();
      for (const auto& [name, range] : k.items) {
        json item = {{"type", "number"}, {"description", name}};
        add_range(item, range);
        items.push_back(item);
      }
      s = {{"type", "array"},
           {"prefixItems", items},
           {"items", false},
           {"minItems", k.items.size()},
           {"maxItems", k.items.size()}};
      break;
    }
    case KeyType::object:
      s = object_schema(k);
      break;
    case KeyType::object_array:
      s = {{"type", "array"}, {"items", object_schema(k)}};
      if (k.min_items > 0) s["minItems"] = k.min_items;
      if (k.max_items != std::numeric_limits<std::size_t>::max()) s["maxItems"] = k.max_items;
      break;
    case KeyType::string_array:
      s = {{"type", "array"}, {"items", {{"type", "string"}, {"minLength", 1}}}};
      break;
    case KeyType::choice_or_object:
      s["anyOf"] = json::array({{{"type", "string"}, {"enum", k.choices}}, object_schema(k)});
      break;
    case KeyType::map:
      s = {{"type", "object"},
           {"minProperties", 1},
           {"additionalProperties", key_schema(k.children[0])}};
      break;
  }
  if (k.nullable && k.type != KeyType::choice_or_object && k.type != KeyType::spectral &&
      s.contains("type"))
    s["type"] = json::array({s["type"], "null"});
  if (!k.only.is_null()) s["const"] = k.only;
  if (!k.default_value.is_null()) s["default"] = k.default_value;
  s["description"] = schema_description(k);
  return s;
}

json object_schema(const Key& k) {
  json s = {{"type", "object"}, {"additionalProperties", false}};
  json properties = json::object();
  json required = json::array();
  for (const Key& c : k.children) {
    properties[c.name] = key_schema(c);
    if (c.required) required.push_back(c.name);
  }
  s["properties"] = properties;
  if (!required.empty()) s["required"] = required;
  return s;
}

}  // namespace

json configuration_schema() {
  const Key& root = configuration_keys();
  json s = {{"$schema", "https://json-schema.org/draft/2020-12/schema"},
            {"title", "glaswave configuration"},
            {"description", root.description + " (glaswave " GLASWAVE_VERSION ")"}};
  s.update(object_schema(root));
  // Exactly one of `dem`, `plane` and `point_cloud` (which is true when given: its declaration's
  // `const`), as the parser asks.
  json one_of = json::array();
  const std::vector<std::string> grounds = {"dem", "plane", "point_cloud"};
  for (const std::string& ground : grounds) {
    json others = json::array();
    for (const std::string& other : grounds)
      if (other != ground) others.push_back({{"required", {other}}});
    one_of.push_back({{"required", {ground}}, {"not", {{"anyOf", others}}}});
  }
  json& terrain = s["properties"]["terrain"];
  terrain["oneOf"] = one_of;
  return s;
}

// ---- the README's table ---------------------------------------------------------------------

namespace {

std::string code(const std::string& text) { return "`" + text + "`"; }

std::string default_cell(const Key& k) {
  if (k.type == KeyType::object || k.type == KeyType::object_array || k.type == KeyType::map) {
    if (!k.default_text.empty()) return k.default_text;
    return "—";
  }
  if (k.default_value.is_null()) return k.default_text.empty() ? "—" : k.default_text;
  const json& v = k.default_value;
  if (v.is_string()) return code(v.get<std::string>());
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  if (v.is_number_float()) return format_number(v.get<double>());
  if (v.is_number()) return v.dump();
  if (v.is_array() && k.type == KeyType::number_pair)
    return "[" + format_number(v[0].get<double>()) + ", " + format_number(v[1].get<double>()) + "]";
  return code(v.dump());
}

std::string integer_text(const Key& k) {
  std::string text = "integer ≥ " + std::to_string(k.min);
  if (k.max != static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max()) &&
      k.max != std::numeric_limits<std::uint64_t>::max() && k.max != int_max)
    text = "integer in [" + std::to_string(k.min) + ", " + std::to_string(k.max) + "]";
  return text;
}

std::string allowed_cell(const Key& k) {
  std::string choices;
  for (std::size_t i = 0; i < k.choices.size(); ++i)
    choices += (i ? ", " : "") + code(k.choices[i]);
  if (!k.only.is_null()) return k.only.dump() + " only";
  switch (k.type) {
    case KeyType::number:
      return k.range.low || k.range.high ? "number " + k.range.interval() : "number";
    case KeyType::integer:
      return integer_text(k);
    case KeyType::boolean:
      return "true, false";
    case KeyType::string:
      if (!k.choices.empty()) return k.open_choices ? choices + " or " + k.what_else : choices;
      if (k.format == "date-time") return "ISO 8601 UTC time";
      if (k.format == "path") return "file path";
      return "string";
    case KeyType::spectral:
      return "number " + k.range.interval() + ", or an object of one per band";
    case KeyType::number_pair:
      return "[min, max], each " + k.range.interval();
    case KeyType::number_tuple: {
      std::string names, ranges;
      for (const auto& [name, range] : k.items) {
        names += (names.empty() ? "" : ", ") + name;
        ranges += (ranges.empty() ? "" : ", ") + name + " " + range.interval();
      }
      return "[" + names + "]: " + ranges;
    }
    case KeyType::object:
      return k.nullable && k.default_text == "null" ? "object or null" : "object";
    case KeyType::object_array: {
      std::string text = "array of objects";
      if (k.max_items != std::numeric_limits<std::size_t>::max())
        text += " (" + std::to_string(k.min_items) + " to " + std::to_string(k.max_items) + ")";
      else if (k.min_items > 0)
        text += " (at least " + std::to_string(k.min_items) + ")";
      return text;
    }
    case KeyType::choice_or_object:
      return choices + ", or an object";
    case KeyType::string_array:
      return "array of strings";
    case KeyType::map:
      return "object of `" + k.children[0].name + "`: " + allowed_cell(k.children[0]);
  }
  return "";
}

void add_rows(const Key& k, const std::string& prefix, std::ostringstream& out) {
  for (const Key& c : k.children) {
    const std::string name = prefix + c.name;
    if (c.name != "$schema") {
      std::string meaning = c.description;
      if (c.required) meaning = "required; " + meaning;
      out << "| " << code(name) << " | " << allowed_cell(c) << " | " << default_cell(c) << " | "
          << (c.unit.empty() ? "—" : c.unit) << " | " << meaning << " |\n";
    }
    if (c.type == KeyType::object || c.type == KeyType::choice_or_object)
      add_rows(c, name + ".", out);
    if (c.type == KeyType::object_array) add_rows(c, name + "[].", out);
    if (c.type == KeyType::map && c.children[0].type == KeyType::object)
      add_rows(c.children[0], name + "." + c.children[0].name + ".", out);
  }
}

}  // namespace

std::string configuration_keys_markdown() {
  std::ostringstream out;
  out << "| key | allowed | default | unit | meaning |\n|---|---|---|---|---|\n";
  add_rows(configuration_keys(), "", out);
  return out.str();
}

}  // namespace glaswave
