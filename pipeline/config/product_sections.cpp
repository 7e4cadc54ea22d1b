// The readers of what the commands write (their keys: product_keys.cpp): `output` with the
// switches its writers declare and the rules across its products, `brf`, `table`.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>

#include "core/error.hpp"
#include "core/part_switch.hpp"
#include "pipeline/config/json_reader.hpp"
#include "pipeline/config/json_text.hpp"
#include "pipeline/config/keys.hpp"
#include "pipeline/config/section_readers.hpp"

namespace glaswave {

using nlohmann::json;

namespace {

// output.geojson is the old name of output.footprints (which also writes a GeoPackage): read
// into it with a warning, and written into the resolved configuration under the new name.
void read_old_footprints_key(JsonReader& r, OutputSettings& o, std::vector<std::string>& warnings) {
  if (!r.has("geojson")) return;
  if (r.has("footprints"))
    r.fail("geojson", "is the old name of output.footprints: give footprints alone");
  o.footprints = r.boolean("geojson");
  r.resolved().erase("geojson");
  r.resolved()["footprints"] = o.footprints;
  warnings.push_back(r.place("geojson") +
                     ": is now output.footprints (the old name still works, for now)");
}

// RAMI-IV's lidar measurements: names ROMC knows, a model and experiment that make file names, and
// height bins that hold whole window bins.
void check_rami_lidar(const Config& config) {
  const RamiLidarSettings& rami = *config.output.rami;
  if (rami.measurements.empty())
    throw config_error("/output/rami/measurements", "names no measurement");
  for (const std::string& m : rami.measurements) {
    if (m != "lidar_sgl_co" && m != "lidar_tot")
      throw config_error("/output/rami/measurements",
                         "'" + m +
                             "' is not a lidar measurement glaswave writes (lidar_sgl_co, "
                             "lidar_tot)");
    if (m == "lidar_sgl_co" && !config.output.per_order)
      throw config_error("/output/per_order",
                         "lidar_sgl_co is the light scattered once: output.rami needs "
                         "output.per_order true for it");
  }
  const std::string model = rami.model.empty() ? "glaswave" : rami.model;  // absent: its default
  if (model.size() > 10 || !std::all_of(model.begin(), model.end(),
                                        [](unsigned char c) { return std::isalnum(c) != 0; }))
    throw config_error("/output/rami/model",
                       "ROMC's model identifier is 1 to 10 letters and digits");
  if (rami.experiment.empty()) throw config_error("/output/rami/experiment", "is required");
  if (rami.experiment.find_first_of("/\\ ") != std::string::npos)
    throw config_error("/output/rami/experiment",
                       "must not hold '/', '\\' or spaces (a file name)");
  if (config.sensor.bands.size() > 1 && rami.experiment.find("{band}") == std::string::npos)
    throw config_error("/output/rami/experiment",
                       "needs '{band}' with more than one band: an experiment is one band's");
  if (!receiver_traits_of(config.sensor).waveform) {
    const auto waveform = [](const ReceiverTraits& t) { return t.waveform; };
    throw config_error("/output/rami", "RAMI's lidar measurements need the " +
                                           alternatives(declared_kinds<ReceiverTraits>(waveform)) +
                                           " receiver");
  }
  if (config.atmosphere)
    throw config_error("/output/rami",
                       "RAMI's lidar measurements are of the canopy alone: not beside "
                       "`atmosphere`");
  if (config.detector.enabled)
    throw config_error("/output/rami",
                       "RAMI's lidar measurements are the noise-free return: not with "
                       "detector.enabled");
  // A window bin spans c bin_ns / 2 of height at nadir.
  const double window_bin_m = 0.5 * 299792458.0 * config.sensor.bin_ns * 1e-9;
  const double ratio = rami.height_bin_m / window_bin_m;
  if (ratio < 1.0 - 1e-6 || std::abs(ratio - std::round(ratio)) > 1e-6 * ratio) {
    char why[240];
    std::snprintf(why, sizeof why,
                  "%.6g m is not a whole number of the window's bins of %.6g m (c bin_ns / 2); "
                  "sensor.bin_ns %.9g gives 10 of them",
                  rami.height_bin_m, window_bin_m,
                  rami.height_bin_m / 10.0 * 2.0 / 299792458.0 * 1e9);
    throw config_error("/output/rami/height_bin_m", why);
  }
}

}  // namespace

OutputSettings read_output(JsonReader& root, std::vector<std::string>& warnings) {
  OutputSettings o;
  JsonReader r = root.object("output");
  read_fields(r, {{"geojson", [&] { read_old_footprints_key(r, o, warnings); }}}, o);
  for (const auto& entry : Registry<PartSwitch>::instance().entries())  // declared by the parts
    if (entry.make.section == "output") o.switches[entry.name] = r.boolean(entry.name);
  r.finish();
  return o;
}

BrfSettings read_brf(JsonReader& root) {
  BrfSettings b;
  JsonReader r = root.object("brf");
  read_fields(r, {}, b);
  r.finish();
  return b;
}

TableSettings read_table(JsonReader& root) {
  TableSettings t;
  JsonReader r = root.object("table");
  // An object of at least one entry, or absent.
  const auto entries_of = [&](const std::string& key) -> const json* {
    const json& value = r.raw(key);
    if (value.is_null()) return nullptr;
    if (!value.is_object() || value.empty())
      r.fail(key, "must be an object of at least one key, got " + describe(value));
    return &value;
  };
  const auto read_vary = [&] {
    const json* vary = entries_of("vary");
    if (!vary) return;
    for (const auto& [name, range] : vary->items()) {
      const std::string place = json_pointer_child(r.place("vary"), name);
      if (!range.is_array() || range.size() != 2)
        throw config_error(place, "must be [low, high], got " + describe(range));
      const double low = read_number(place + "/0", range[0], any_finite());
      const double high = read_number(place + "/1", range[1], any_finite());
      if (!(low <= high)) throw config_error(place, "must be [low, high] with low <= high");
      t.vary.push_back({name, {low, high}});
      r.resolved()["vary"][name] = range;
    }
  };
  const auto read_values = [&] {
    const json* values = entries_of("values");
    if (!values) return;
    for (const auto& [name, list] : values->items()) {
      const std::string place = json_pointer_child(r.place("values"), name);
      if (!list.is_array() || list.empty())
        throw config_error(place, "must be an array of at least one value, got " + describe(list));
      std::vector<std::string> texts;
      for (const json& value : list) {
        if (!value.is_string() || value.get<std::string>().empty())
          throw config_error(place,
                             "each value must be a non-empty string (read as --set reads "
                             "VALUE), got " +
                                 describe(value));
        texts.push_back(value.get<std::string>());
      }
      t.values.push_back({name, std::move(texts)});
      r.resolved()["values"][name] = list;
    }
  };
  read_fields(r, {{"vary", read_vary}, {"values", read_values}}, t);
  r.finish();
  for (const auto& [name, range] : t.vary)
    for (const auto& [other, list] : t.values)
      if (name == other)
        r.fail("values", "`" + name + "` is both varied over a range and given values");
  return t;
}

void check_outputs(const Config& config) {
  const OutputSettings& o = config.output;
  // The ICESat-2 granules of a receiver that flies ATLAS's beams are products of their own.
  const bool granules = receiver_traits_of(config.sensor).atlas_beams &&
                        (o.atl03.value_or(true) || o.atl08.value_or(true));
  if (!o.netcdf && !o.footprints && !granules && !o.rami)
    throw config_error("/output",
                       "nothing to write: output.netcdf and output.footprints are both false");
  if (o.plots && !(o.netcdf && o.footprints))
    throw config_error(
        "/output/plots",
        "plots are drawn from shots.nc and footprints.geojson: they need output.netcdf "
        "and output.footprints");
  if (o.plots && !o.metrics)
    throw config_error("/output/metrics",
                       "plots draw the Gaussian fits and ground estimates: output.plots needs "
                       "output.metrics");
  if (o.plots && o.footprints_format != "GeoJSON")
    throw config_error("/output/footprints_format",
                       "plots are drawn from footprints.geojson: output.plots needs "
                       "footprints_format \"GeoJSON\", got \"" +
                           o.footprints_format + "\"");
  if (o.rami) check_rami_lidar(config);
}

}  // namespace glaswave
