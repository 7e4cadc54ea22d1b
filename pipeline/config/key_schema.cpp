// The configuration's JSON Schema (draft 2020-12), generated from the declaration of its keys.
#include "pipeline/config/keys.hpp"

namespace glaswave {

using nlohmann::json;

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

}  // namespace glaswave
