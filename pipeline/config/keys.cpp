// The key model: ranges, the builders of declarations, and the whole configuration's
// declaration put together from its sections (sensor_keys.cpp, scene_keys.cpp,
// product_keys.cpp), each key declared beside the member it sets (key_fields.hpp). Defaults that
// the settings structs already hold are taken from their member initialisers, so that each
// default is written once. The JSON Schema and the table of keys are generated from it
// (key_schema.cpp, key_table.cpp).
#include "pipeline/config/keys.hpp"

#include "pipeline/config/config.hpp"
#include "pipeline/config/key_fields.hpp"

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

namespace declare {

Key make(std::string name, KeyType type, std::string unit, std::string description) {
  Key k;
  k.name = std::move(name);
  k.type = type;
  k.unit = std::move(unit);
  k.description = std::move(description);
  return k;
}

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

// ---- the declaration ------------------------------------------------------------------------

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
         section_keys::sensor_keys(), section_keys::atmosphere_keys(),
         section_keys::simulation_keys(), section_keys::terrain_keys(), section_keys::canopy_keys(),
         section_keys::track_keys(), section_keys::with_part_switches(section_keys::output_keys()),
         section_keys::detector_keys(), section_keys::brf_keys(), section_keys::table_keys()});
  }();
  return root;
}

}  // namespace glaswave
