// The configuration parser: JSON document -> typed settings, each section read by its reader
// (sensor_sections.cpp, scene_sections.cpp, product_sections.cpp) through the declaration of its
// keys, presets expanded, every error at its JSON path; then the checks across keys and the
// memory check; relative paths resolved against the configuration's folder.
#include "pipeline/config/config.hpp"

#include <utility>

#include "core/error.hpp"
#include "pipeline/config/cross_checks.hpp"
#include "pipeline/config/json_reader.hpp"
#include "pipeline/config/json_text.hpp"
#include "pipeline/config/keys.hpp"
#include "pipeline/config/section_readers.hpp"
#include "pipeline/config/stands_file.hpp"

namespace glaswave {

using nlohmann::json;

namespace {

// A relative path of the configuration is taken relative to the configuration file's folder, so
// that a configuration runs the same from any working directory.
void resolve_path(std::string& path, json& resolved_section, const char* key,
                  const std::filesystem::path& folder) {
  if (path.empty() || std::filesystem::path(path).is_absolute()) return;
  path = std::filesystem::absolute(folder / path).lexically_normal().string();
  resolved_section[key] = path;
}

}  // namespace

Config parse_config(const json& document) {
  if (!document.is_object())
    throw config_error("", "the configuration must be a JSON object, got " + describe(document));
  Config c;
  c.resolved = json::object();
  JsonReader root(document, "", c.resolved, configuration_keys());
  root.optional_string("$schema");  // lets an editor find the schema; not a setting
  c.seed = root.unsigned_integer("seed");
  // The sensor first: its bands give the per-band optical properties their length.
  c.sensor = read_sensor(root);
  c.atmosphere = read_atmosphere(root, c.sensor.bands);
  if (c.atmosphere) set_band_transmissions(c.sensor, *c.atmosphere);
  c.simulation = read_simulation(root);
  // A missing terrain is told after every other section is read and the unknown keys are
  // refused, so that a wrong value given ({"canopy": {"pai": -1}}) or a misspelt "terrian" is
  // named before the section not given.
  const bool terrain_given = root.has("terrain");
  if (terrain_given) c.terrain = read_terrain(root, c.sensor.bands);
  c.canopy = read_canopy(root, c.sensor.bands);
  c.track = read_track(root, c.sensor);
  c.output = read_output(root, c.warnings);
  // The ICESat-2 granules are those of a receiver that flies ATLAS's beams: asked of another,
  // nothing.
  if (!receiver_traits_of(c.sensor).atlas_beams)
    for (const auto& [key, asked] : {std::pair{"atl03", c.output.atl03}, {"atl08", c.output.atl08}})
      if (asked.value_or(false))
        c.warnings.push_back(
            "/output/" + std::string(key) + ": the " + c.sensor.receiver +
            " receiver writes no ICESat-2 granule; it is written with sensor.receiver " +
            receivers_that([](const ReceiverTraits& t) { return t.atlas_beams; }));
  c.detector = read_detector(root);
  c.brf = read_brf(root);
  c.table = read_table(root);
  root.finish();
  if (!terrain_given)
    root.fail("terrain", "is required: give \"dem\", \"plane\" or \"point_cloud\"");
  c.resolved.erase("$schema");
  check_across_keys(document, c);
  check_shot_size(c);
  return c;
}

Config load_config(const std::filesystem::path& file, const std::vector<std::string>& overrides) {
  return load_config_document(read_json_file(file), file.parent_path(), overrides);
}

Config load_config_document(json document, const std::filesystem::path& folder,
                            const std::vector<std::string>& overrides) {
  for (const std::string& assignment : overrides) apply_override(document, assignment);
  Config c = parse_config(document);
  json& r = c.resolved;
  resolve_path(c.terrain.dem, r["terrain"], "dem", folder);
  if (c.canopy) {
    resolve_path(c.canopy->crowns_file, r["canopy"], "crowns_file", folder);
    resolve_path(c.canopy->stands, r["canopy"], "stands", folder);
    if (!c.canopy->voxels_file.empty())
      resolve_path(c.canopy->voxels_file, r["canopy"]["voxels"], "file", folder);
    if (!c.canopy->point_cloud_file.empty())
      resolve_path(c.canopy->point_cloud_file, r["canopy"]["point_cloud"], "file", folder);
    if (!c.canopy->facet_trees_file.empty()) {
      json& facets = r["canopy"]["facets"];
      resolve_path(c.canopy->facet_trees_file, facets, "trees_file", folder);
      for (auto& [name, file] : c.canopy->facet_models)
        resolve_path(file, facets["models"], name.c_str(), folder);
    }
  }
  resolve_path(c.track.ephemeris, r["track"], "ephemeris", folder);
  resolve_path(c.track.granule, r["track"], "file", folder);
  if (c.canopy && !c.canopy->stands.empty())
    c.canopy->stand_areas = read_stands(c.canopy->stands, r["canopy"], c.sensor.bands);
  return c;
}

}  // namespace glaswave
