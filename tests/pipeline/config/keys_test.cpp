// Tests of the one declaration of keys: the JSON Schema generated from it names exactly the keys
// the parser accepts, with their ranges; the manual's table is the one generated from it; the
// parser cannot read a key that is not declared; the sizes a run cannot hold are refused, the
// limit in the message; and the rules of `run`'s outputs that `check` shares.
#include "pipeline/config/keys.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "core/error.hpp"
#include "pipeline/config/config.hpp"
#include "pipeline/config/json_reader.hpp"
#include "pipeline/config/presets.hpp"
#include "tests/pipeline/config/config_test_support.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

using nlohmann::json;
using test_support::doc;
using test_support::error_of;
using ::testing::HasSubstr;
using ::testing::StartsWith;

std::string run_error_of(const json& document) {
  try {
    check_outputs(parse_config(document));
  } catch (const Error& e) {
    EXPECT_EQ(e.exit_status(), 2);
    return e.what();
  }
  return "";
}

// Configurations that between them use every key of the contract.
std::vector<json> rich_documents() {
  return {
      doc(R"({"$schema": "x", "seed": 5, "sensor": {"preset": "glas"},
          "simulation": {"rays_per_shot": 10, "max_order": 3},
          "terrain": {"plane": {"slope_deg": 10}, "roughness": {"rms_m": 0.5},
                      "soil_reflectance": {"532": 0.1, "1064": 0.3}},
          "canopy": {"lad": {"ellipsoidal_mean_deg": 30}, "crowns_file": "c.csv"},
          "track": {"type": "points", "points": [{"lat_deg": 1, "lon_deg": 2}]},
          "output": {"per_order": true, "footprints_format": "GeoJSON"},
          "detector": {"enabled": true, "bits": 8, "saturation_W": 1e-3},
          "brf": {"views": [{"zenith_deg": 10, "azimuth_deg": 20}]}})"),
      doc(R"({"terrain": {"dem": "/d.tif", "dem_band": 2, "vertical_datum": "egm96"},
          "canopy": {"stands": "/s.geojson"},
          "track": {"type": "orbit", "epoch": "2001-01-01T00:00:00Z"}})"),
      doc(R"({"track": {"type": "ephemeris", "ephemeris": "/e.csv"}})"),
      doc(R"({"track": {"spacing_m": 100}})"),
  };
}

// The schema of the value at a JSON path of a configuration, or null when the schema has none.
const json* schema_at(const json& schema, const std::vector<std::string>& path) {
  const json* s = &schema;
  for (const std::string& part : path) {
    if (s->contains("anyOf"))  // a name or an object: the object's keys
      for (const json& alternative : (*s)["anyOf"])
        if (alternative.contains("properties")) s = &alternative;
    if (s->contains("properties")) {
      if (!(*s)["properties"].contains(part)) return nullptr;
      s = &(*s)["properties"][part];
    } else if (s->contains("items")) {
      s = &(*s)["items"];  // an array element: part is its index
      if (!s->contains("properties") || !(*s)["properties"].contains(part)) return nullptr;
      s = &(*s)["properties"][part];
    } else {
      return nullptr;
    }
  }
  return s;
}

// Every key of a resolved configuration, as its path of names (array elements skipped over).
void key_paths(const json& value, std::vector<std::string> path,
               std::vector<std::vector<std::string>>& out, bool opaque = false) {
  if (value.is_object() && !opaque) {
    for (const auto& [key, child] : value.items()) {
      std::vector<std::string> p = path;
      p.push_back(key);
      out.push_back(p);
      // Per-band objects and the lad object have keys of their own kind.
      const bool per_band = key.find("reflectance") != std::string::npos ||
                            key.find("transmittance") != std::string::npos;
      key_paths(child, p, out, per_band);
    }
  } else if (value.is_array()) {
    for (const json& element : value)
      if (element.is_object()) key_paths(element, path, out);
  }
}

// ---- the JSON Schema ------------------------------------------------------------------------

TEST(Schema, IsWellFormedJsonOfDraft202012) {
  const json schema = configuration_schema();
  EXPECT_EQ(schema["$schema"], "https://json-schema.org/draft/2020-12/schema");
  EXPECT_EQ(schema["type"], "object");
  EXPECT_EQ(schema["additionalProperties"], false);
  EXPECT_EQ(schema["required"], json::array({"terrain"}));
  // Ranges as the parser checks them (PRODUCT.md section 5).
  EXPECT_EQ(schema.at(json::json_pointer("/properties/canopy/properties/pai/minimum")), 0);
  EXPECT_EQ(schema.at(json::json_pointer("/properties/canopy/properties/pai/default")), 3.0);
  EXPECT_EQ(schema.at(json::json_pointer("/properties/canopy/properties/cover/maximum")), 1);
  EXPECT_EQ(
      schema.at(json::json_pointer("/properties/simulation/properties/rays_per_shot/minimum")), 1);
  EXPECT_EQ(
      schema.at(json::json_pointer("/properties/track/properties/off_nadir_deg/exclusiveMaximum")),
      45);
  EXPECT_EQ(schema.at(json::json_pointer("/properties/sensor/properties/pulse_sigma_ns/minimum")),
            0.001);
  EXPECT_EQ(schema.at(json::json_pointer("/properties/track/properties/type/enum")),
            json::array({"pass", "points", "orbit", "ephemeris", "granule"}));
  EXPECT_EQ(
      schema.at(json::json_pointer("/properties/output/properties/footprints_format/default")),
      "GeoJSON");
  // Descriptions carry the unit.
  EXPECT_THAT(schema.at(json::json_pointer("/properties/sensor/properties/bin_ns/description"))
                  .get<std::string>(),
              HasSubstr("(unit: ns)"));
  // A per-band value: a number, or an object of numbers, each in [0, 1].
  const json& leaf =
      schema.at(json::json_pointer("/properties/canopy/properties/leaf_reflectance"));
  ASSERT_TRUE(leaf.contains("anyOf"));
  EXPECT_EQ(leaf["anyOf"][0]["type"], "number");
  EXPECT_EQ(leaf["anyOf"][0]["maximum"], 1);
  EXPECT_EQ(leaf["anyOf"][1]["type"], "object");
  EXPECT_EQ(leaf["anyOf"][1]["additionalProperties"]["minimum"], 0);
  // The canopy may be null (bare ground).
  EXPECT_EQ(schema.at(json::json_pointer("/properties/canopy/type")),
            json::array({"object", "null"}));
}

TEST(Schema, EveryObjectRefusesUnknownKeys) {
  std::function<void(const json&, const std::string&)> walk = [&](const json& s,
                                                                  const std::string& where) {
    if (!s.is_object()) return;
    if (s.contains("properties")) {
      EXPECT_EQ(s.value("additionalProperties", json(true)), false) << where;
    }
    for (const auto& [key, child] : s.items()) {
      if (child.is_object()) walk(child, where + "/" + key);
      if (child.is_array())
        for (const json& element : child) walk(element, where + "/" + key);
    }
  };
  walk(configuration_schema(), "");
}

// What the parser accepts, it finds in the schema: every key of resolved configurations (which
// hold every key read, defaults filled in) has a schema of its own.
TEST(Schema, NamesEveryKeyTheParserAccepts) {
  const json schema = configuration_schema();
  std::set<std::string> seen;
  for (const json& document : rich_documents()) {
    std::vector<std::vector<std::string>> paths;
    key_paths(parse_config(document).resolved, {}, paths);
    for (const auto& path : paths) {
      std::string name;
      for (const std::string& part : path) name += "/" + part;
      EXPECT_NE(schema_at(schema, path), nullptr) << name << " is accepted but not in the schema";
      seen.insert(name);
    }
  }
  EXPECT_GT(seen.size(), 80u);  // the documents do reach every section
}

// And what the schema names, the parser accepts: each key of the schema, given its default (or
// null where it has none), is never an unknown key.
TEST(Schema, TheParserAcceptsEveryKeyOfTheSchema) {
  const json schema = configuration_schema();
  int keys = 0;
  std::function<void(const json&, const std::vector<std::string>&)> walk =
      [&](const json& s, const std::vector<std::string>& path) {
        if (!s.contains("properties")) return;
        for (const auto& [key, child] : s["properties"].items()) {
          std::vector<std::string> p = path;
          p.push_back(key);
          json d = doc("{}");
          json* node = &d;
          for (const std::string& part : p) node = &(*node)[part];
          if (child.contains("default")) *node = child["default"];
          if (p.front() == "terrain" && p.size() > 1 && p[1] != "plane")
            d["terrain"]["plane"] = json::object();
          std::string name;
          for (const std::string& part : p) name += "/" + part;
          EXPECT_THAT(error_of(d), ::testing::Not(HasSubstr("unknown key"))) << name;
          ++keys;
          walk(child, p);
        }
      };
  walk(schema, {});
  EXPECT_GT(keys, 70);
}

// Defaults and ranges come from the declaration: the schema's say what the parser does.
TEST(Schema, DefaultsAreWhatTheParserFillsIn) {
  const json schema = configuration_schema();
  const json resolved = parse_config(doc(R"({"canopy": {}})")).resolved;
  for (const std::string section : {"simulation", "canopy", "output", "detector", "brf"}) {
    for (const auto& [key, s] : schema["properties"][section]["properties"].items()) {
      if (s.contains("default")) {
        EXPECT_EQ(resolved[section][key], s["default"]) << section << "/" << key;
      }
    }
  }
  // The sensor's defaults are the default preset's values.
  const json preset = json::parse(sensor_presets().at(default_sensor_preset));
  for (const auto& [key, value] : preset.items())
    EXPECT_EQ(schema["properties"]["sensor"]["properties"][key]["default"], value) << key;
}

// An independent check of the schema through Python's jsonschema: it is a valid draft 2020-12
// schema, resolved configurations validate, and bad ones do not. Without jsonschema the test
// fails, not skips: a skip reads as a pass in the suite's summary, and the schema would go
// unchecked unseen. scripts/setup installs it (python3-jsonschema), for /usr/bin/python3.
TEST(Schema, ValidatesWithPythonJsonschema) {
  ASSERT_EQ(std::system("/usr/bin/python3 -c 'import jsonschema'"), 0)
      << "the schema cannot be checked: /usr/bin/python3 cannot import jsonschema (install "
         "python3-jsonschema, as scripts/setup does)";
  const test_support::ScratchDir dir("glaswave_schema_test");
  std::ofstream(dir / "schema.json") << configuration_schema().dump();
  json good = json::array(), bad = json::array();
  for (const json& document : rich_documents()) {
    good.push_back(document);
    good.push_back(parse_config(document).resolved);
  }
  // A point cloud's ground, and that ground beside another or false.
  const json cloud = doc(R"({"terrain": {"point_cloud": true},
                             "canopy": {"point_cloud": {"file": "plot.las"}}})");
  good.push_back(cloud);
  good.push_back(parse_config(cloud).resolved);
  bad.push_back(doc(R"({"terrain": {"plane": {}, "point_cloud": true},
                        "canopy": {"point_cloud": {"file": "plot.las"}}})"));
  bad.push_back(doc(R"({"terrain": {"point_cloud": false}})"));
  bad.push_back(doc(R"({"canopy": {"pai": -1}})"));
  bad.push_back(doc(R"({"canopy": {"pia": 1}})"));
  bad.push_back(doc(R"({"output": {"footprints_format": "shapefile"}})"));
  bad.push_back(doc(R"({"terrain": {"dem": "a.tif", "plane": {}}})"));
  bad.push_back(doc(R"({"canopy": {"leaf_reflectance": {"532": 2}}})"));
  std::ofstream(dir / "good.json") << good.dump();
  std::ofstream(dir / "bad.json") << bad.dump();
  const std::string script =
      "import json, sys, jsonschema\n"
      "d = sys.argv[1]\n"
      "schema = json.load(open(d + '/schema.json'))\n"
      "jsonschema.Draft202012Validator.check_schema(schema)\n"
      "v = jsonschema.Draft202012Validator(schema)\n"
      "for i, doc in enumerate(json.load(open(d + '/good.json'))):\n"
      "    v.validate(doc)\n"
      "for i, doc in enumerate(json.load(open(d + '/bad.json'))):\n"
      "    assert not v.is_valid(doc), i\n";
  std::ofstream(dir / "check.py") << script;
  const int status = std::system(
      ("/usr/bin/python3 " + (dir / "check.py").string() + " " + dir.path().string()).c_str());
  EXPECT_EQ(status, 0);
}

// ---- the manual's table --------------------------------------------------------------------

// The rows of a Markdown table of keys ("| `key` | ..."), without headers and section titles.
std::string key_rows(const std::string& markdown) {
  std::istringstream in(markdown);
  std::string line, rows;
  while (std::getline(in, line))
    if (line.rfind("| `", 0) == 0) rows += line + "\n";
  return rows;
}

TEST(Manual, KeyTableIsTheOneGeneratedFromTheDeclaration) {
  const auto page = std::filesystem::path(GLASWAVE_SOURCE_DIR) / "docs/reference/configuration.md";
  std::ifstream in(page);
  ASSERT_TRUE(in) << page;
  std::stringstream text;
  text << in.rdbuf();
  const std::string manual = text.str();
  const std::string begin = "<!-- generated:keys:begin -->\n", end = "<!-- generated:keys:end -->";
  const auto from = manual.find(begin);
  const auto to = manual.find(end);
  ASSERT_NE(from, std::string::npos);
  ASSERT_NE(to, std::string::npos);
  const std::string table = key_rows(manual.substr(from + begin.size(), to - from - begin.size()));
  // The first line that differs, rather than two pages of table.
  std::istringstream in_manual(table), in_declaration(key_rows(configuration_keys_markdown()));
  std::string manual_line, declared_line;
  for (int line = 1;; ++line) {
    const bool more_manual = static_cast<bool>(std::getline(in_manual, manual_line));
    const bool more_declared = static_cast<bool>(std::getline(in_declaration, declared_line));
    if (!more_manual && !more_declared) break;
    if (!more_manual) manual_line = "(the manual's table ends)";
    if (!more_declared) declared_line = "(the declaration's table ends)";
    ASSERT_EQ(manual_line, declared_line)
        << "row " << line << " of the manual's table of keys differs from the declaration in "
        << "pipeline/config/keys.cpp: run ./scripts/docs-reference";
  }
  // Every key of the schema has its row.
  const nlohmann::json schema = configuration_schema();  // the loop below must not outlive it
  for (const auto& [key, s] : schema["properties"]["canopy"]["properties"].items())
    EXPECT_THAT(table, HasSubstr("| `canopy." + key + "` |")) << key;
}

// A key that accepts one value of its type (terrain.point_cloud: true, false being refused) says
// so where it is declared, and the schema, the reference's table and the parser take it from
// there: the table listed "true, false" while the parser refused false.
TEST(Manual, AKeyOfOneValueSaysSoInTheSchemaTheTableAndTheParser) {
  const Key* point_cloud = configuration_keys().child("terrain")->child("point_cloud");
  ASSERT_NE(point_cloud, nullptr);
  EXPECT_EQ(point_cloud->only, json(true));
  const json schema = configuration_schema();
  EXPECT_EQ(schema["properties"]["terrain"]["properties"]["point_cloud"]["const"], json(true));
  EXPECT_THAT(configuration_keys_markdown(), HasSubstr("| `terrain.point_cloud` | true only |"));
  EXPECT_THAT(error_of(doc(R"({"terrain": {"point_cloud": false}})")),
              StartsWith("/terrain/point_cloud: must be true"));
}

// ---- the parser reads through the declaration -----------------------------------------------

TEST(Declaration, ReadingAnUndeclaredKeyIsABug) {
  const Key declaration =
      declare::object("", "test", {declare::number("x", 1.0, at_least(0), "m", "x")});
  const json document = {{"x", 2}};
  json resolved;
  JsonReader reader(document, "", resolved, declaration);
  EXPECT_EQ(reader.number("x"), 2.0);
  EXPECT_THROW(reader.number("y"), std::logic_error);
  EXPECT_THROW(reader.integer("x"), std::logic_error);  // declared as a number
  EXPECT_THROW(reader.raw("z"), std::logic_error);
}

TEST(Declaration, DefaultsAndRangesComeFromIt) {
  const Key declaration =
      declare::object("", "test",
                      {declare::number("a_m", 2.5, closed(0, 3), "m", "a"),
                       declare::integer("n", 4, 1, 10, "", "n"), declare::boolean("b", true, "b"),
                       declare::choice("c", "one", {"one", "two"}, "c")});
  json resolved;
  const json empty = json::object();
  JsonReader defaults(empty, "/t", resolved, declaration);
  EXPECT_EQ(defaults.number("a_m"), 2.5);
  EXPECT_EQ(defaults.integer("n"), 4);
  EXPECT_TRUE(defaults.boolean("b"));
  EXPECT_EQ(defaults.choice<int>("c", {{"one", 1}, {"two", 2}}), 1);
  const json bad = {{"a_m", 4}, {"n", 11}, {"c", "three"}};
  JsonReader reader(bad, "/t", resolved, declaration);
  try {
    reader.number("a_m");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "/t/a_m: must be in [0, 3], got 4");
  }
  EXPECT_THROW(reader.integer("n"), Error);
  EXPECT_THROW((reader.choice<int>("c", {{"one", 1}, {"two", 2}})), Error);
}

// ---- sizes a run cannot hold ----------------------------------------------------------------

TEST(RunSize, TheLimitIsInTheMessage) {
  EXPECT_EQ(error_of(doc(R"({"sensor": {"bins": 16777217}})")),
            "/sensor/bins: must be <= 16777216, got 16777217");
  EXPECT_EQ(error_of(doc(R"({"simulation": {"rays_per_shot": 1e13}})")),
            "/simulation/rays_per_shot: must be <= 1000000000, got 10000000000000.0");
  EXPECT_EQ(error_of(doc(R"({"track": {"shots": 2e9}})")),
            "/track/shots: must be <= 1000000000, got 2000000000.0");
  json many = doc("{}");
  for (int i = 0; i < 257; ++i)
    many["sensor"]["bands"].push_back({{"name", std::to_string(i)},
                                       {"wavelength_nm", 532},
                                       {"pulse_energy_mJ", 1},
                                       {"atmos_transmission_roundtrip", 1}});
  EXPECT_EQ(error_of(many), "/sensor/bands: must have at most 256 elements, got 257");
  // 2 bands x (300000 + 60) bins x 3 waveforms x 8 bytes = 14.4 MiB, over 4 MiB.
  EXPECT_EQ(error_of(doc(R"({"sensor": {"bins": 300000}})")),
            "/sensor/bins: a shot's waveforms would take 13.7 MiB (2 bands x 300000 bins + 60 bins "
            "of pulse margin x 3 waveforms x 8 bytes), more than the limit of 4 MiB a shot");
  // A pulse far wider than the bins (both at their bounds): its margin is what does not fit.
  EXPECT_THAT(error_of(doc(R"({"sensor": {"pulse_sigma_ns": 1000, "bin_ns": 1e-3}})")),
              StartsWith("/sensor/pulse_sigma_ns: a shot's waveforms would take"));
  // Per-order waveforms multiply it.
  EXPECT_THAT(error_of(doc(R"({"sensor": {"bins": 20000}, "simulation": {"max_order": 100},
      "output": {"per_order": true}})")),
              StartsWith("/output/per_order: a shot's waveforms would take"));
  EXPECT_EQ(error_of(doc(R"({"sensor": {"bins": 20000}, "simulation": {"max_order": 100}})")), "");
  EXPECT_EQ(error_of(doc(R"({"sensor": {"bins": 80000}})")), "");  // 3.7 MiB
}

// ---- what run asks beyond a configuration that simulates -------------------------------------

TEST(CheckRun, OutputsAndFormats) {
  EXPECT_EQ(run_error_of(doc("{}")), "");
  EXPECT_EQ(run_error_of(doc(R"({"output": {"netcdf": false, "footprints": false}})")),
            "/output: nothing to write: output.netcdf and output.footprints are both false");
  EXPECT_THAT(run_error_of(doc(R"({"output": {"plots": true, "footprints": false}})")),
              StartsWith("/output/plots: plots are drawn from shots.nc and footprints.geojson"));
  EXPECT_EQ(run_error_of(doc(R"({"output": {"footprints_format": "GPKG"}})")), "");
  EXPECT_EQ(run_error_of(doc(R"({"output": {"footprints_format": "GPKG", "plots": true}})")),
            "/output/footprints_format: plots are drawn from footprints.geojson: output.plots "
            "needs footprints_format \"GeoJSON\", got \"GPKG\"");
  EXPECT_EQ(run_error_of(doc(R"({"output": {"footprints_format": "GPKG", "footprints": false}})")),
            "");
  EXPECT_EQ(error_of(doc(R"({"output": {"footprints_format": "gpkg"}})")),
            "/output/footprints_format: must be one of GeoJSON, GPKG, got \"gpkg\"; did you mean "
            "\"GPKG\"?");
  EXPECT_EQ(parse_config(doc("{}")).output.footprints_format, "GeoJSON");
}

}  // namespace
}  // namespace glaswave
