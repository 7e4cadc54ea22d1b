// A path-aware reader of one JSON object of the configuration: each key is read through its
// declaration (pipeline/config/keys.hpp), which gives its type, default and range, where the
// settings member is assigned; the value used is recorded into the resolved configuration, and
// keys nobody asked for are rejected at the end.
#pragma once

#include <cstdint>
#include <functional>
#include <initializer_list>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <typeinfo>
#include <utility>
#include <vector>

#include "core/names.hpp"
#include "pipeline/config/keys.hpp"

namespace glaswave {

// How deep objects and arrays may nest in JSON text the program reads (a configuration, a --set
// value, a stand's field): the deepest key of a configuration is 4 levels down, and
// nlohmann-json's serializer and copies recurse, so a deeper value would overflow the stack.
inline constexpr std::size_t max_json_depth = 64;

// Parses JSON text as nlohmann-json does, and also refuses, before anything recurses, nesting
// deeper than max_json_depth and an object that gives a key twice: a config_error at the JSON
// pointer of the place (under `prefix`), "nests deeper than 64 levels" or "duplicate key".
// Malformed text throws nlohmann-json's parse_error, a number that overflows its out_of_range.
nlohmann::json parse_json_checked(const std::string& text, const std::string& prefix = "");

// The JSON pointer of `key` inside the object at `path` ("/canopy" + "pai" -> "/canopy/pai"),
// with '~' and '/' escaped as RFC 6901 asks.
std::string json_pointer_child(const std::string& path, const std::string& key);

// A value for an error message: compact JSON, as a bounded excerpt (core/excerpt.hpp).
std::string describe(const nlohmann::json& value);

// A number for an error message: no trailing zeros, no binary noise ("1.2", not
// "1.2000000000000002").
std::string format_number(double x);

// The message for an unknown key: the nearest known key when it is close enough to be a typo,
// else the list of known keys.
std::string unknown_key_message(const std::string& key, const std::vector<std::string>& known);

class JsonReader {
 public:
  // `object` is the JSON at `path` (null stands for an absent object: every key takes its
  // default), declared by `declaration` (an object, an array of objects or the object form of a
  // choice); `resolved` receives the values as used. Throws when `object` is neither an object
  // nor null.
  JsonReader(const nlohmann::json& object, std::string path, nlohmann::json& resolved,
             const Key& declaration);

  const std::string& path() const { return path_; }
  const Key& declaration() const { return *declaration_; }
  std::string place(const std::string& key) const { return json_pointer_child(path_, key); }

  // The declaration of a key of this object. Reading a key that is not declared, or as another
  // type than declared, is a bug of the parser: std::logic_error.
  const Key& declared(const std::string& key, KeyType type) const;

  // Whether the key is present and not null. Declares the key as known.
  bool has(const std::string& key);

  // Throws "is required" at the key when it is absent or null.
  void require(const std::string& key);

  // The raw value of a key (null when absent), for keys with a shape of their own. Declares the
  // key as known; the caller writes what it used into resolved().
  const nlohmann::json& raw(const std::string& key);

  // Each reads a key with its declared default and range; `fallback` replaces the declared
  // default where the default depends on other keys. A key declared required and absent is an
  // error.
  double number(const std::string& key);
  double number(const std::string& key, double fallback);
  std::optional<double> optional_number(const std::string& key);
  std::int64_t integer(const std::string& key);
  std::optional<std::int64_t> optional_integer(const std::string& key);
  std::uint64_t unsigned_integer(const std::string& key);
  bool boolean(const std::string& key);
  std::string string(const std::string& key);
  std::string string(const std::string& key, const std::string& fallback);
  std::optional<std::string> optional_string(const std::string& key);
  // An array of non-empty strings; empty when absent.
  std::vector<std::string> string_array(const std::string& key);

  // A string that names one of the declared choices, each mapped to its value by `values`.
  template <typename T>
  T choice(const std::string& key, const std::vector<std::pair<std::string, T>>& values) {
    const Key& k = declared(key, KeyType::string);
    const std::string name = string(key);
    for (const std::string& known : k.choices) {
      if (known != name) continue;
      for (const auto& [value_name, value] : values)
        if (value_name == name) return value;
      throw_undeclared(key);
    }
    throw_not_one_of(key, name, k.choices);
  }

  // The keys the object holds, as given (for keys that exclude the others).
  std::vector<std::string> given() const;

  // A nested object (absent or null reads as empty, so its keys take their defaults).
  JsonReader object(const std::string& key);

  // An array of objects, required and of the length its declaration says (`required` may ask
  // for it where other keys make it so). Each element gets its own reader, whose finish() the
  // caller calls.
  std::vector<JsonReader> object_array(const std::string& key);
  std::vector<JsonReader> object_array(const std::string& key, bool required);

  // A map (KeyType::map) of named entries, in the order given; empty when absent (an error when
  // required). path_map: each value a file path; object_map: each value an object, given its
  // own reader, whose finish() the caller calls.
  std::vector<std::pair<std::string, std::string>> path_map(const std::string& key);
  std::vector<std::pair<std::string, JsonReader>> object_map(const std::string& key);

  // Values as used at this level.
  nlohmann::json& resolved() { return resolved_; }

  // Rejects every key of the object that was never asked for.
  void finish() const;

  // An error at `key` inside this object.
  [[noreturn]] void fail(const std::string& key, const std::string& message) const;
  [[noreturn]] void throw_not_one_of(const std::string& key, const std::string& got,
                                     const std::vector<std::string>& names) const;

 private:
  const nlohmann::json* find(const std::string& key);
  const nlohmann::json* find_required(const std::string& key, const Key& k);
  [[noreturn]] void throw_undeclared(const std::string& key) const;

  const nlohmann::json* object_;  // null when the object is absent
  std::string path_;
  nlohmann::json& resolved_;
  const Key* declaration_;
  std::vector<std::string> known_;
};

// A section's own reading of a key whose value needs more than its member (other keys, a check
// across keys, a shape of its own), by the key's name.
using KeyHooks = std::vector<std::pair<std::string, std::function<void()>>>;

// One settings struct a section's keys are read into.
struct SettingsTarget {
  const std::type_info* type;
  void* object;
};

// Reads the keys of the reader's object in the order of their declaration, so that the first
// fault named is the first in the file's order: a key declared with a member of one of `targets`
// is read into it (keys.cpp's Fields), then the hook of its name runs; a key with no member is
// read by its hook, or left to the caller. The caller calls finish(). A hook for a key that is
// not declared is a bug of the parser: std::logic_error.
void read_declared(JsonReader& reader, const KeyHooks& hooks,
                   std::initializer_list<SettingsTarget> targets);

// The same for the settings structs `settings`.
template <typename... S>
void read_fields(JsonReader& reader, const KeyHooks& hooks, S&... settings) {
  read_declared(reader, hooks, {SettingsTarget{&typeid(S), &settings}...});
}

// Checks a number found at `place`: a finite JSON number within `range`.
double read_number(const std::string& place, const nlohmann::json& value, const Range& range);

// Checks an integer found at `place`: integral, within [min, max].
std::int64_t read_integer(const std::string& place, const nlohmann::json& value, std::int64_t min,
                          std::int64_t max);

}  // namespace glaswave
