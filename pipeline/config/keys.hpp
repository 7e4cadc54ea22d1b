// The one declaration of every configuration key: its type, default, unit, range and
// description (PDAL's declared options are the model). The parser reads each key through its
// declaration, and the JSON Schema (`glaswave check --schema`) and the README's table of keys
// are generated from it, so a default or a range is written in one place only.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <typeinfo>
#include <utility>
#include <vector>

namespace glaswave {

class JsonReader;

// The allowed interval of a number; open or closed at each end, either end optional.
struct Range {
  std::optional<double> low;
  std::optional<double> high;
  bool low_open = false;
  bool high_open = false;

  bool contains(double x) const;
  // "must be >= 0", "must be in (0, 1]", or empty when anything finite goes.
  std::string requirement() const;
  // "≥ 0", "(0, 1]" for a table; empty when anything finite goes.
  std::string interval() const;
};

Range any_finite();
Range at_least(double low);                  // [low, inf)
Range above(double low);                     // (low, inf)
Range closed(double low, double high);       // [low, high]
Range half_open(double low, double high);    // [low, high)
Range open_closed(double low, double high);  // (low, high]
Range open(double low, double high);         // (low, high)

enum class KeyType {
  number,            // a finite number within `range`
  integer,           // an integer within [min, max]
  boolean,           // true or false
  string,            // a string; one of `choices` when they are given (and `open_choices` is false)
  spectral,          // a number within `range` for every band, or an object keyed by band name
  number_pair,       // [min, max], both within `range`, min <= max
  number_tuple,      // a fixed number of numbers, each named and within its own range
  object,            // an object whose keys are `children`
  object_array,      // an array of objects whose keys are `children`
  choice_or_object,  // one of `choices`, or an object whose keys are `children`
  string_array,      // an array of non-empty strings
  map,               // an object of entries the user names, each value as `children[0]` says
};

struct Key {
  std::string name;
  KeyType type = KeyType::number;
  std::string description;
  std::string unit;              // empty: none
  nlohmann::json default_value;  // null: none, see default_text
  std::string default_text;      // what the default is when it is not one value ("`start_time`")
  Range range;                   // number, spectral, number_pair
  std::int64_t min = 0;          // integer
  std::uint64_t max = static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max());
  std::vector<std::string> choices;  // string, choice_or_object
  bool open_choices = false;  // the choices are examples of a wider set (`what_else` says which)
  std::string what_else;      // "a vertical CRS as AUTH:CODE", with `pattern` for the schema
  std::string pattern;
  std::string format;  // "date-time" for times, "path" for files
  // The one value accepted, where the type allows others (terrain.point_cloud: true, since false
  // would leave no ground); null: any value of the type. The schema's `const`.
  nlohmann::json only;
  bool required = false;
  bool nullable = false;  // null reads as absent
  std::size_t min_items = 0, max_items = std::numeric_limits<std::size_t>::max();  // arrays
  std::vector<Key> children;  // object, object_array, choice_or_object
  // number_tuple: the name and range of each number, in order.
  std::vector<std::pair<std::string, Range>> items;
  // The member the key sets, for keys declared with one (keys.cpp's Fields): `read` reads the
  // key through the reader into that member of a settings struct of type `owner`. Keys whose
  // value needs other keys have none: their section reads them (read_fields' hooks).
  const std::type_info* owner = nullptr;
  std::function<void(JsonReader&, void* settings)> read;

  // The declared key `name` among the children, or null.
  const Key* child(const std::string& name) const;

  // Modifiers for the declaration's builders.
  Key&& with_required() &&;
  Key&& with_nullable() &&;
  Key&& with_default_text(std::string text) &&;
  Key&& with_items(std::size_t least, std::size_t most) &&;
  Key&& with_default(nlohmann::json value) &&;
  Key&& with_only(nlohmann::json value) &&;
};

// Builders of declarations: each gives the name, the default, the range and unit, and what the
// key means. A default given as the settings' own member initialiser keeps it in one place.
namespace declare {
// A key of `type` with nothing but its name, unit and description (a choice_or_object's, whose
// section sets the rest).
Key make(std::string name, KeyType type, std::string unit, std::string description);
Key number(std::string name, std::optional<double> fallback, Range range, std::string unit,
           std::string description);
Key integer(std::string name, std::optional<std::int64_t> fallback, std::int64_t min,
            std::uint64_t max, std::string unit, std::string description);
Key boolean(std::string name, bool fallback, std::string description);
Key string(std::string name, std::optional<std::string> fallback, std::string description);
Key choice(std::string name, std::optional<std::string> fallback, std::vector<std::string> choices,
           std::string description);
Key time(std::string name, std::optional<std::string> fallback, std::string description);
Key path(std::string name, std::string description);
Key string_array(std::string name, std::string description);
Key spectral(std::string name, double fallback, Range range, std::string unit,
             std::string description);
Key number_pair(std::string name, std::array<double, 2> fallback, Range range, std::string unit,
                std::string description);
// A fixed array of numbers, each named and with its own range (hg2's [g1, g2, w]).
Key number_tuple(std::string name, std::vector<std::pair<std::string, Range>> items,
                 std::string unit, std::string description);
Key object(std::string name, std::string description, std::vector<Key> children);
Key object_array(std::string name, nlohmann::json fallback, std::string description,
                 std::vector<Key> item_keys);
// An object of named entries (`{"oak": "oak.obj"}`), at least one; `value` declares each entry's
// value, its name (`NAME`) standing for the entry's in tables.
Key map(std::string name, std::string description, Key value);
}  // namespace declare

// The declaration of the whole configuration: the root object.
const Key& configuration_keys();

// The JSON Schema (draft 2020-12) of a configuration, generated from the declaration.
nlohmann::json configuration_schema();

// The README's table of keys (Markdown), generated from the declaration.
std::string configuration_keys_markdown();

}  // namespace glaswave
