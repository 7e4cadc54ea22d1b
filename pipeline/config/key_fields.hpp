// For the files that declare the configuration's keys (keys.cpp and its sections' *_keys.cpp)
// alone: the binder that declares a key beside the member it sets, and each section's
// declaration, which configuration_keys() puts together.
#pragma once

#include <cstdint>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <type_traits>
#include <typeinfo>
#include <utility>
#include <vector>

#include "pipeline/config/json_reader.hpp"
#include "pipeline/config/keys.hpp"

namespace glaswave {

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
    Key k = declare::make(std::move(name), KeyType::boolean, "", std::move(description));
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
    // Absent: the member's default, which the key reference shows (given empty: empty, for the
    // section's checks to refuse where a list must name something).
    return bind(std::move(k), member,
                [initial = initial_.*member](JsonReader& r, const std::string& key) {
                  const bool given = r.has(key);
                  std::vector<std::string> names = r.string_array(key);
                  return given ? names : initial;
                });
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
  Key object_array(std::string name, std::vector<M> S::*member, nlohmann::json fallback,
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
  // Value-initialised through S's own constructor: aggregate initialisation (`initial_{}`) put
  // every member's construction and unwinding inline here, where GCC 12 saw SensorSettings'
  // beam_profile as maybe uninitialised on the unwinding path (a false -Wmaybe-uninitialized).
  const S initial_ = S();
};

namespace section_keys {

inline constexpr std::uint64_t int_max =
    static_cast<std::uint64_t>(std::numeric_limits<int>::max());

// The sections, in sensor_keys.cpp, scene_keys.cpp and product_keys.cpp.
Key sensor_keys();
Key atmosphere_keys();
Key detector_keys();
Key simulation_keys();
Key terrain_keys();
Key canopy_keys();
Key track_keys();
Key output_keys();
Key brf_keys();
Key table_keys();

// `section` with the switches parts declare in it (core/part_switch.hpp) after its own keys;
// its reader reads them into its settings' `switches`.
Key with_part_switches(Key section);

}  // namespace section_keys
}  // namespace glaswave
