// The path-aware JSON reader of the configuration: type and range checks, error messages that
// name the JSON pointer of the offending key, and unknown-key rejection with a suggestion.
#include "pipeline/config/json_reader.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <stdexcept>
#include <unordered_set>

#include "core/error.hpp"
#include "core/excerpt.hpp"
#include "core/input_file.hpp"
#include "core/names.hpp"

namespace glaswave {

using nlohmann::json;

std::string json_pointer_child(const std::string& path, const std::string& key) {
  std::string escaped;
  // A place names a key the user gave, which may be of any length: an excerpt of it.
  for (char c : key.size() > excerpt_max_chars ? excerpt(key) : key) {
    if (c == '~')
      escaped += "~0";
    else if (c == '/')
      escaped += "~1";
    else
      escaped += c;
  }
  return path + "/" + escaped;
}

namespace {

// What a parse has opened and not yet closed: one frame an object or array, with the keys an
// object gave so far and the index an array has reached. A SAX pass of its own over the text:
// nlohmann-json's callback parser walks a parent's members at the end of each child object
// (looking for one it discarded), so an object of n objects took n^2 steps (65 537 materials:
// half a minute); this pass and the plain parse after it are linear.
class NestingCheck : public nlohmann::json_sax<json> {
 public:
  explicit NestingCheck(std::string prefix) : prefix_(std::move(prefix)) {}

  bool null() override { return value(); }
  bool boolean(bool) override { return value(); }
  bool number_integer(number_integer_t) override { return value(); }
  bool number_unsigned(number_unsigned_t) override { return value(); }
  bool number_float(number_float_t, const string_t&) override { return value(); }
  bool string(string_t&) override { return value(); }
  bool binary(binary_t&) override { return value(); }
  bool start_object(std::size_t) override { return open(true); }
  bool start_array(std::size_t) override { return open(false); }
  bool end_object() override { return close(); }
  bool end_array() override { return close(); }

  bool key(string_t& name) override {
    Frame& frame = stack_.back();
    frame.key = name;
    frame.keyed = true;
    if (!frame.keys.insert(frame.key).second)
      throw config_error(pointer(stack_.size()),
                         "duplicate key: the object gives " + quoted_excerpt(frame.key) + " twice");
    return true;
  }

  // The plain parse that follows throws the parser's own error for the same text.
  bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception&) override {
    return false;
  }

 private:
  struct Frame {
    bool object;
    bool keyed;  // an object: whether a key was read
    std::string key;
    std::size_t index;
    std::unordered_set<std::string> keys;
  };

  bool open(bool object) {
    // The place named is the outermost levels only: the message stays one short line.
    if (stack_.size() >= max_json_depth)
      throw config_error(
          pointer(3) + "/...",
          "nests deeper than " + std::to_string(max_json_depth) + " levels of objects and arrays");
    stack_.push_back({object, false, "", 0, {}});
    return true;
  }

  bool close() {
    stack_.pop_back();
    return value();
  }

  bool value() {
    if (!stack_.empty() && !stack_.back().object) ++stack_.back().index;
    return true;
  }

  // The JSON pointer of the value being read, through its outermost `levels` levels.
  std::string pointer(std::size_t levels) const {
    std::string p = prefix_;
    for (std::size_t i = 0; i < std::min(levels, stack_.size()); ++i) {
      const Frame& f = stack_[i];
      if (f.object && !f.keyed) break;
      p = f.object ? json_pointer_child(p, f.key) : p + "/" + std::to_string(f.index);
    }
    return p;
  }

  std::string prefix_;
  std::vector<Frame> stack_;
};

}  // namespace

json parse_json_checked(const std::string& text, const std::string& prefix) {
  NestingCheck check(prefix);
  json::sax_parse(text, &check);
  return json::parse(text);
}

std::string describe(const json& value) {
  // nlohmann-json writes non-finite numbers as null, which would hide the cause.
  if (value.is_number_float() && !std::isfinite(value.get<double>())) {
    const double x = value.get<double>();
    return std::isnan(x) ? "nan" : x > 0 ? "inf" : "-inf";
  }
  // Replace invalid UTF-8 rather than throw while building an error message.
  if (value.is_string()) return quoted_excerpt(value.get<std::string>());
  return excerpt(value.dump(-1, ' ', false, json::error_handler_t::replace));
}

std::string format_number(double x) {
  // 12 significant digits hide the noise of sums such as 0.7 + 0.5 while keeping every value a
  // user is likely to type.
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.12g", x);
  return buffer;
}

std::string unknown_key_message(const std::string& key, const std::vector<std::string>& known) {
  std::string message = "unknown key " + quoted_excerpt(key);
  if (const std::string suggestion = did_you_mean(key, known); !suggestion.empty())
    return message + suggestion;
  if (known.empty()) return message + "; this object takes no keys";
  std::vector<std::string> sorted = known;
  std::sort(sorted.begin(), sorted.end());
  message += "; known keys: ";
  for (std::size_t i = 0; i < sorted.size(); ++i) message += (i ? ", " : "") + sorted[i];
  return message;
}

double read_number(const std::string& place, const json& value, const Range& range) {
  if (!value.is_number()) throw config_error(place, "must be a number, got " + describe(value));
  const double x = value.get<double>();
  // nlohmann-json reads 1e999 as infinity; no setting of the model means that.
  if (!std::isfinite(x))
    throw config_error(place, "must be a finite number, got " + describe(value));
  if (!range.contains(x))
    throw config_error(place, range.requirement() + ", got " + describe(value));
  return x;
}

std::int64_t read_integer(const std::string& place, const json& value, std::int64_t min,
                          std::int64_t max) {
  std::int64_t n = 0;
  if (value.is_number_integer() && !value.is_number_unsigned()) {
    n = value.get<std::int64_t>();
  } else if (value.is_number_unsigned()) {
    const std::uint64_t u = value.get<std::uint64_t>();
    if (u > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max()))
      throw config_error(place, "must be <= " + std::to_string(max) + ", got " + describe(value));
    n = static_cast<std::int64_t>(u);
  } else if (value.is_number_float()) {
    // 1e4 is an integer written in exponent form; 2.5 is not.
    const double x = value.get<double>();
    if (!std::isfinite(x))
      throw config_error(place, "must be a finite number, got " + describe(value));
    if (x != std::floor(x)) throw config_error(place, "must be an integer, got " + describe(value));
    // Beyond the range it is an integer out of range, not "not an integer" (2^64 read as a
    // double is one).
    if (x > static_cast<double>(max))
      throw config_error(place, "must be <= " + std::to_string(max) + ", got " + describe(value));
    if (x < static_cast<double>(min))
      throw config_error(place, "must be >= " + std::to_string(min) + ", got " + describe(value));
    if (std::fabs(x) > 9.0e15)  // within the range, but a double's digits may not be its own
      throw config_error(place, "must be an integer written in digits, got " + describe(value));
    n = static_cast<std::int64_t>(x);
  } else {
    throw config_error(place, "must be an integer, got " + describe(value));
  }
  if (n < min)
    throw config_error(place, "must be >= " + std::to_string(min) + ", got " + describe(value));
  if (n > max)
    throw config_error(place, "must be <= " + std::to_string(max) + ", got " + describe(value));
  return n;
}

JsonReader::JsonReader(const json& object, std::string path, json& resolved, const Key& declaration)
    : object_(object.is_null() ? nullptr : &object),
      path_(std::move(path)),
      resolved_(resolved),
      declaration_(&declaration) {
  if (object_ && !object_->is_object())
    throw config_error(path_, "must be an object, got " + describe(*object_));
  if (!resolved_.is_object()) resolved_ = json::object();
}

void JsonReader::throw_undeclared(const std::string& key) const {
  throw std::logic_error("the configuration parser reads " + place(key) +
                         " as it is not declared among its keys (pipeline/config/*_keys.cpp)");
}

const Key& JsonReader::declared(const std::string& key, KeyType type) const {
  const Key* k = declaration_->child(key);
  if (!k || k->type != type) throw_undeclared(key);
  return *k;
}

const json* JsonReader::find(const std::string& key) {
  if (!declaration_->child(key)) throw_undeclared(key);
  if (std::find(known_.begin(), known_.end(), key) == known_.end()) known_.push_back(key);
  if (!object_) return nullptr;
  auto it = object_->find(key);
  if (it == object_->end()) return nullptr;
  return &*it;
}

// The value of a key; null when absent (or null where null means absent); "is required" when a
// required key is absent.
const json* JsonReader::find_required(const std::string& key, const Key& k) {
  const json* value = find(key);
  if (value && value->is_null() && k.nullable) value = nullptr;
  if (!value && k.required) fail(key, "is required");
  return value;
}

bool JsonReader::has(const std::string& key) {
  const json* value = find(key);
  return value && !value->is_null();
}

void JsonReader::require(const std::string& key) {
  if (!has(key)) fail(key, "is required");
}

const json& JsonReader::raw(const std::string& key) {
  static const json null_value;
  const json* value = find(key);
  return value ? *value : null_value;
}

double JsonReader::number(const std::string& key) {
  const Key& k = declared(key, KeyType::number);
  if (k.default_value.is_null() && !k.required) throw_undeclared(key);  // optional_number
  return number(key, k.required ? 0.0 : k.default_value.get<double>());
}

double JsonReader::number(const std::string& key, double fallback) {
  const Key& k = declared(key, KeyType::number);
  const json* value = find_required(key, k);
  const double x = value ? read_number(place(key), *value, k.range) : fallback;
  resolved_[key] = value ? *value : json(x);
  return x;
}

std::optional<double> JsonReader::optional_number(const std::string& key) {
  const Key& k = declared(key, KeyType::number);
  const json* value = find(key);
  if (!value || value->is_null()) return std::nullopt;
  const double x = read_number(place(key), *value, k.range);
  resolved_[key] = *value;
  return x;
}

std::int64_t JsonReader::integer(const std::string& key) {
  const Key& k = declared(key, KeyType::integer);
  const json* value = find_required(key, k);
  const auto max = static_cast<std::int64_t>(
      std::min<std::uint64_t>(k.max, std::numeric_limits<std::int64_t>::max()));
  const std::int64_t n =
      value ? read_integer(place(key), *value, k.min, max) : k.default_value.get<std::int64_t>();
  resolved_[key] = n;
  return n;
}

std::optional<std::int64_t> JsonReader::optional_integer(const std::string& key) {
  const Key& k = declared(key, KeyType::integer);
  const json* value = find(key);
  if (!value || value->is_null()) return std::nullopt;
  const auto max = static_cast<std::int64_t>(
      std::min<std::uint64_t>(k.max, std::numeric_limits<std::int64_t>::max()));
  const std::int64_t n = read_integer(place(key), *value, k.min, max);
  resolved_[key] = n;
  return n;
}

std::uint64_t JsonReader::unsigned_integer(const std::string& key) {
  const Key& k = declared(key, KeyType::integer);
  const json* value = find(key);
  if (!value) {
    const auto fallback = k.default_value.get<std::uint64_t>();
    resolved_[key] = fallback;
    return fallback;
  }
  // Unsigned values beyond the signed range are legal here (a 64-bit seed); beyond 2^64 - 1 JSON
  // holds the integer as a double, which is too large, not "not an integer".
  constexpr double two_to_64 = 18446744073709551616.0;
  if (value->is_number_float() && value->get<double>() >= two_to_64 &&
      value->get<double>() == std::floor(value->get<double>()))
    fail(key,
         "is too large: must be <= " + std::to_string(std::numeric_limits<std::uint64_t>::max()) +
             ", got " + describe(*value));
  const std::uint64_t n =
      value->is_number_unsigned()
          ? value->get<std::uint64_t>()
          : static_cast<std::uint64_t>(
                read_integer(place(key), *value, 0, std::numeric_limits<std::int64_t>::max()));
  resolved_[key] = n;
  return n;
}

bool JsonReader::boolean(const std::string& key) {
  const Key& k = declared(key, KeyType::boolean);
  const json* value = find(key);
  if (value && !value->is_boolean())
    fail(key, "must be a boolean (true or false), got " + describe(*value));
  const bool b = value ? value->get<bool>() : k.default_value.get<bool>();
  resolved_[key] = b;
  return b;
}

std::string JsonReader::string(const std::string& key) {
  const Key& k = declared(key, KeyType::string);
  return string(key, k.default_value.is_string() ? k.default_value.get<std::string>() : "");
}

std::string JsonReader::string(const std::string& key, const std::string& fallback) {
  const Key& k = declared(key, KeyType::string);
  const json* value = find_required(key, k);
  if (value && !value->is_string()) fail(key, "must be a string, got " + describe(*value));
  std::string s = value ? value->get<std::string>() : fallback;
  // A file's path is cut at a NUL byte by every C library below: the file before it would be read.
  if (k.format == "path") require_no_nul(s, place(key), ErrorKind::config);
  resolved_[key] = s;
  return s;
}

std::optional<std::string> JsonReader::optional_string(const std::string& key) {
  const Key& k = declared(key, KeyType::string);
  const json* value = find(key);
  if (!value || value->is_null()) return std::nullopt;
  if (!value->is_string()) fail(key, "must be a string, got " + describe(*value));
  if (k.format == "path")
    require_no_nul(value->get_ref<const std::string&>(), place(key), ErrorKind::config);
  resolved_[key] = *value;
  return value->get<std::string>();
}

std::vector<std::string> JsonReader::string_array(const std::string& key) {
  const Key& k = declared(key, KeyType::string_array);
  const json* value = find_required(key, k);
  std::vector<std::string> strings;
  if (value && !value->is_null()) {
    if (!value->is_array()) fail(key, "must be an array of strings, got " + describe(*value));
    for (const json& item : *value) {
      if (!item.is_string() || item.get<std::string>().empty())
        fail(key, "must be an array of non-empty strings, got " + describe(item) + " in it");
      strings.push_back(item.get<std::string>());
    }
  }
  resolved_[key] = strings;
  return strings;
}

JsonReader JsonReader::object(const std::string& key) {
  const Key& k = declared(key, KeyType::object);
  const json& value = raw(key);
  if (!value.is_null() && !value.is_object())
    fail(key, "must be an object, got " + describe(value));
  return JsonReader(value, place(key), resolved_[key], k);
}

std::vector<JsonReader> JsonReader::object_array(const std::string& key) {
  return object_array(key, declared(key, KeyType::object_array).required);
}

std::vector<JsonReader> JsonReader::object_array(const std::string& key, bool required) {
  const Key& k = declared(key, KeyType::object_array);
  const json& value = raw(key);
  if (value.is_null()) {
    if (required) fail(key, "is required");
    return {};
  }
  if (!value.is_array()) fail(key, "must be an array, got " + describe(value));
  if (value.size() < k.min_items)
    fail(key, k.min_items == 1 ? "must not be empty"
                               : "must have at least " + std::to_string(k.min_items) + " elements");
  if (value.size() > k.max_items)
    fail(key, "must have at most " + std::to_string(k.max_items) + " elements, got " +
                  std::to_string(value.size()));
  // Size the resolved array first: readers keep references to its elements.
  json& out = resolved_[key];
  out = json::array();
  for (std::size_t i = 0; i < value.size(); ++i) out.push_back(json::object());
  std::vector<JsonReader> readers;
  readers.reserve(value.size());
  const std::string array_place = place(key);
  for (std::size_t i = 0; i < value.size(); ++i) {
    const std::string element_place = array_place + "/" + std::to_string(i);
    if (!value[i].is_object())
      throw config_error(element_place, "must be an object, got " + describe(value[i]));
    readers.emplace_back(value[i], element_place, out[i], k);
  }
  return readers;
}

namespace {

// The map's object, checked: an object of at least one entry, or null when absent.
const json* map_object(JsonReader& reader, const std::string& key, const Key& k) {
  const json& value = reader.raw(key);
  if (value.is_null()) {
    if (k.required) reader.fail(key, "is required");
    return nullptr;
  }
  if (!value.is_object())
    reader.fail(key, "must be an object of named entries, got " + describe(value));
  if (value.empty()) reader.fail(key, "must name at least one entry");
  return &value;
}

}  // namespace

std::vector<std::pair<std::string, std::string>> JsonReader::path_map(const std::string& key) {
  const Key& k = declared(key, KeyType::map);
  std::vector<std::pair<std::string, std::string>> entries;
  const json* value = map_object(*this, key, k);
  if (!value) return entries;
  json& out = resolved_[key];
  out = json::object();
  for (const auto& [name, entry] : value->items()) {
    const std::string entry_place = json_pointer_child(place(key), name);
    if (!entry.is_string() || entry.get<std::string>().empty())
      throw config_error(entry_place, "must be a file path, got " + describe(entry));
    require_no_nul(entry.get_ref<const std::string&>(), entry_place, ErrorKind::config);
    entries.emplace_back(name, entry.get<std::string>());
    out[name] = entry;
  }
  return entries;
}

std::vector<std::pair<std::string, JsonReader>> JsonReader::object_map(const std::string& key) {
  const Key& k = declared(key, KeyType::map);
  std::vector<std::pair<std::string, JsonReader>> entries;
  const json* value = map_object(*this, key, k);
  if (!value) return entries;
  // Size the resolved object first: readers keep references to its members.
  json& out = resolved_[key];
  out = json::object();
  for (const auto& [name, entry] : value->items()) out[name] = json::object();
  for (const auto& [name, entry] : value->items()) {
    const std::string entry_place = json_pointer_child(place(key), name);
    if (!entry.is_object())
      throw config_error(entry_place, "must be an object, got " + describe(entry));
    entries.emplace_back(name, JsonReader(entry, entry_place, out[name], k.children[0]));
  }
  return entries;
}

std::vector<std::string> JsonReader::given() const {
  std::vector<std::string> keys;
  if (object_)
    for (const auto& [key, value] : object_->items()) keys.push_back(key);
  return keys;
}

void JsonReader::finish() const {
  if (!object_) return;
  for (const auto& [key, value] : object_->items()) {
    if (std::find(known_.begin(), known_.end(), key) == known_.end())
      throw config_error(json_pointer_child(path_, key), unknown_key_message(key, known_));
  }
}

void read_declared(JsonReader& reader, const KeyHooks& hooks,
                   std::initializer_list<SettingsTarget> targets) {
  const Key& declaration = reader.declaration();
  for (const auto& [name, hook] : hooks)
    if (!declaration.child(name))
      throw std::logic_error("the configuration parser reads " + reader.place(name) +
                             " as it is not declared among its keys (pipeline/config/*_keys.cpp)");
  for (const Key& key : declaration.children) {
    if (key.read)
      for (const SettingsTarget& target : targets)
        if (*target.type == *key.owner) key.read(reader, target.object);
    for (const auto& [name, hook] : hooks)
      if (name == key.name) hook();
  }
}

void JsonReader::fail(const std::string& key, const std::string& message) const {
  throw config_error(place(key), message);
}

void JsonReader::throw_not_one_of(const std::string& key, const std::string& got,
                                  const std::vector<std::string>& names) const {
  std::string list;
  for (std::size_t i = 0; i < names.size(); ++i) list += (i ? ", " : "") + names[i];
  fail(key, "must be one of " + list + ", got " + quoted_excerpt(got) + did_you_mean(got, names));
}

}  // namespace glaswave
