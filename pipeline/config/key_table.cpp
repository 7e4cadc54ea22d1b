// The README's table of keys (Markdown), generated from the declaration of the keys.
#include <sstream>

#include "pipeline/config/key_fields.hpp"
#include "pipeline/config/keys.hpp"

namespace glaswave {

using nlohmann::json;
using section_keys::int_max;

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
