// The forward table: its design, its simulation through the engine's library API, its file.
#include "pipeline/retrieval/forward_table.hpp"

#include <netcdf.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <limits>
#include <mutex>

#include "core/error.hpp"
#include "core/part_kind.hpp"
#include "core/random.hpp"
#include "footprints/receiver_traits.hpp"
#include "pipeline/config/config.hpp"
#include "pipeline/engine/inputs.hpp"
#include "pipeline/retrieval/netcdf_file.hpp"

namespace glaswave {

namespace {

using nlohmann::json;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

constexpr std::array<int, 32> kPrimes = {2,  3,  5,  7,   11,  13,  17,  19,  23,  29, 31,
                                         37, 41, 43, 47,  53,  59,  61,  67,  71,  73, 79,
                                         83, 89, 97, 101, 103, 107, 109, 113, 127, 131};

// Halton's radical inverse of `index` in base `base`.
double radical_inverse(std::uint64_t index, int base) {
  double inverse = 1.0 / base, factor = inverse, value = 0.0;
  while (index > 0) {
    value += static_cast<double>(index % base) * factor;
    index /= base;
    factor *= inverse;
  }
  return value;
}

std::string number_text(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", x);
  return text;
}

// The value text --set takes for parameter p at design value v.
std::string value_text(const TableParameter& p, double v) {
  return p.is_range() ? number_text(v) : p.values.at(static_cast<std::size_t>(v));
}

// The configuration of one entry: its values set as --set sets them, its own seed (another
// forest drawn, other rays), and the detector off: the table holds expected returns, the
// measured shot's own noise is the likelihood's.
Config entry_config(const TableRequest& request, const std::vector<TableParameter>& parameters,
                    const std::vector<double>& values, std::uint64_t seed) {
  json document = request.document;
  for (std::size_t p = 0; p < parameters.size(); ++p)
    apply_override(document, parameters[p].key + "=" + value_text(parameters[p], values[p]));
  document["seed"] = seed;
  if (document.contains("detector") && document["detector"].is_object())
    document["detector"]["enabled"] = false;
  return load_config_document(std::move(document), request.folder, {});
}

// Linear interpolation of `w` (on the decreasing heights `from`) at the heights `to`; 0 outside.
std::vector<double> resample(const std::vector<double>& w, const std::vector<double>& from,
                             const std::vector<double>& to) {
  std::vector<double> out(to.size(), 0.0);
  const std::size_t n = from.size();
  if (n < 2) return out;
  const double step = (from[n - 1] - from[0]) / static_cast<double>(n - 1);
  for (std::size_t j = 0; j < to.size(); ++j) {
    const double x = (to[j] - from[0]) / step;
    if (!(x >= 0.0) || x > static_cast<double>(n - 1)) continue;
    const std::size_t i = std::min(static_cast<std::size_t>(x), n - 2);
    const double f = x - static_cast<double>(i);
    out[j] = (1.0 - f) * w[i] + f * w[i + 1];
  }
  return out;
}

struct EntryResult {
  std::vector<std::vector<double>> waveform_W;  // [band][bin] on the entry's own axis
  std::vector<double> height_m;
  std::vector<double> mc_sd_W;
  std::vector<std::vector<double>> shot0_W;  // [band][bin] the first shot, on the entry's axis
  std::vector<double> energy_canopy_J, energy_ground_J;
  double pai = 0.0, cover = 0.0, height = 0.0, pgap = 0.0;
  double off_nadir_deg = 0.0;
};

EntryResult simulate_entry(const Config& config, std::int64_t shots_wanted,
                           const std::string& place) {
  const std::unique_ptr<Terrain> terrain = open_terrain(config);
  const std::unique_ptr<Track> track = plan_track(config, *terrain);
  const std::unique_ptr<ShotSimulator> simulator = make_shot_simulator(config, *terrain);
  const std::int64_t shots = std::min<std::int64_t>(shots_wanted, track->size());
  const std::size_t bands = config.sensor.bands.size();
  EntryResult entry;
  std::vector<std::vector<std::vector<double>>> per_shot(bands);  // [band][shot][bin]
  entry.energy_canopy_J.assign(bands, 0.0);
  entry.energy_ground_J.assign(bands, 0.0);
  for (std::int64_t k = 0; k < shots; ++k) {
    const ShotRecord record = simulator->simulate(track->footprint(k));
    if (record.quality_flag != quality_good && record.quality_reason <= reason_nodata)
      throw config_error(place, "the track's shot " + std::to_string(k) +
                                    " misses the terrain: a table's shots must meet it");
    const std::size_t bins = record.rx_waveform_W.at(0).size();
    std::vector<double> heights(bins);
    for (std::size_t b = 0; b < bins; ++b)
      heights[b] = record.elev_bin0_m +
                   (record.elev_lastbin_m - record.elev_bin0_m) * static_cast<double>(b) /
                       static_cast<double>(bins - 1) -
                   record.elev_m;
    if (k == 0) {
      entry.height_m = heights;
      entry.off_nadir_deg = record.off_nadir_deg;
    }
    for (std::size_t band = 0; band < bands; ++band) {
      per_shot[band].push_back(resample(record.rx_waveform_W[band], heights, entry.height_m));
      entry.energy_canopy_J[band] += record.rx_energy_canopy_J[band] / shots;
      entry.energy_ground_J[band] += record.rx_energy_ground_J[band] / shots;
    }
    entry.pai += record.pai_true / shots;
    entry.cover += record.cover_true / shots;
    entry.height += record.canopy_height_true_m / shots;
    entry.pgap += record.pgap_true / shots;
  }
  const std::size_t bins = entry.height_m.size();
  for (std::size_t band = 0; band < bands; ++band) {
    std::vector<double> mean(bins, 0.0);
    for (const auto& w : per_shot[band])
      for (std::size_t b = 0; b < bins; ++b) mean[b] += w[b] / shots;
    // One shot's Monte Carlo sd: the scatter of the shots about their mean, over the bins that
    // hold signal (above 1 % of the peak), where the Monte Carlo noise is.
    double sd = kNaN;
    if (shots >= 2) {
      const double peak = *std::max_element(mean.begin(), mean.end());
      double sum = 0.0;
      int counted = 0;
      for (std::size_t b = 0; b < bins; ++b) {
        if (!(mean[b] > 0.01 * peak)) continue;
        for (const auto& w : per_shot[band]) sum += (w[b] - mean[b]) * (w[b] - mean[b]);
        ++counted;
      }
      sd = counted > 0 ? std::sqrt(sum / (counted * static_cast<double>(shots - 1))) : 0.0;
    }
    entry.mc_sd_W.push_back(sd);
    entry.waveform_W.push_back(std::move(mean));
    if (shots >= 2) entry.shot0_W.push_back(per_shot[band][0]);
  }
  return entry;
}

}  // namespace

double design_coordinate(std::uint64_t seed, std::int64_t entry, std::size_t parameter) {
  if (parameter >= kPrimes.size())
    throw config_error("/table", "at most " + std::to_string(kPrimes.size()) + " keys may vary");
  RandomStream shift(seed, parameter, 0, RandomPurpose::table_design);
  // Halton's first point is 0 in every dimension: start at 1.
  const double u =
      radical_inverse(static_cast<std::uint64_t>(entry) + 1, kPrimes[parameter]) + shift.uniform();
  return u - std::floor(u);
}

double implied_rhov_rhog(double energy_canopy, double energy_ground, double cover) {
  if (!(cover > 0.0 && cover < 1.0 && energy_canopy > 0.0 && energy_ground > 0.0)) return kNaN;
  return energy_canopy * (1.0 - cover) / (cover * energy_ground);
}

ForwardTable build_table(const TableRequest& request, const TableProgress& progress) {
  const Config base = load_config_document(request.document, request.folder, {});
  // A receiver that declared it records waveforms (core/part_kind.hpp).
  const auto waveform = [](const ReceiverTraits& t) { return t.waveform; };
  if (!declared_traits<ReceiverTraits>(base.sensor.receiver).value_or(ReceiverTraits{}).waveform)
    throw config_error("/sensor/receiver",
                       "a forward table holds waveforms: the receiver must be " +
                           quoted_alternatives(declared_kinds<ReceiverTraits>(waveform)));
  ForwardTable table;
  for (const auto& [key, range] : base.table.vary)
    table.parameters.push_back({key, range[0], range[1], {}});
  for (const auto& [key, values] : base.table.values)
    table.parameters.push_back({key, 0.0, 0.0, values});
  if (table.parameters.empty())
    throw config_error("/table/vary", "is required: name at least one key to vary");
  if (table.parameters.size() > kPrimes.size())
    throw config_error("/table", "at most " + std::to_string(kPrimes.size()) + " keys may vary");
  table.seed = base.seed;
  table.shots_per_entry = base.table.shots_per_entry;
  table.rays_per_shot = base.simulation.rays_per_shot;
  table.bin_ns = base.sensor.bin_ns;
  table.pulse_sigma_ns = base.sensor.pulse_sigma_ns;
  for (const LidarBand& band : base.sensor.bands) table.band_names.push_back(band.name);
  table.config_json = base.resolved.dump();

  // Every value checked before anything is simulated: each end of a range, each listed value.
  for (std::size_t p = 0; p < table.parameters.size(); ++p) {
    const TableParameter& parameter = table.parameters[p];
    const std::string place =
        (parameter.is_range() ? "/table/vary/" : "/table/values/") + parameter.key;
    std::vector<double> tried = {parameter.low, parameter.high};
    if (!parameter.is_range()) {
      tried.clear();
      for (std::size_t i = 0; i < parameter.values.size(); ++i) tried.push_back(i);
    }
    for (double v : tried) {
      std::vector<double> values(table.parameters.size());
      for (std::size_t q = 0; q < values.size(); ++q)
        values[q] = table.parameters[q].is_range() ? table.parameters[q].low : 0.0;
      values[p] = v;
      try {
        entry_config(request, table.parameters, values, base.seed);
      } catch (const Error& e) {
        throw config_error(
            place, "with " + parameter.key + "=" + value_text(parameter, v) + ": " + e.what());
      }
    }
  }

  const std::int64_t entries = base.table.entries;
  table.parameter_values.resize(entries);
  for (std::int64_t e = 0; e < entries; ++e) {
    for (std::size_t p = 0; p < table.parameters.size(); ++p) {
      const TableParameter& parameter = table.parameters[p];
      const double u = design_coordinate(base.seed, e, p);
      table.parameter_values[e].push_back(
          parameter.is_range() ? parameter.low + u * (parameter.high - parameter.low)
                               : std::min(std::floor(u * parameter.values.size()),
                                          static_cast<double>(parameter.values.size() - 1)));
    }
  }

  std::vector<EntryResult> results(entries);
  std::atomic<std::int64_t> done{0};
  std::mutex progress_mutex;
  const auto simulate = [&](std::int64_t e) {
    const Config config = entry_config(request, table.parameters, table.parameter_values[e],
                                       base.seed + static_cast<std::uint64_t>(e));
    results[e] = simulate_entry(config, table.shots_per_entry, "/track");
    const std::int64_t finished = ++done;
    std::lock_guard lock(progress_mutex);
    if (progress) progress(finished, entries);
  };
  const int cores = tbb::this_task_arena::max_concurrency();
  tbb::task_arena arena(request.threads > 0 ? std::min(request.threads, cores) : cores);
  arena.execute(
      [&] { tbb::parallel_for(std::int64_t{0}, entries, [&](std::int64_t e) { simulate(e); }); });

  // The table's axis: entry 0's, cropped to the bins where some entry has signal (above 1e-6 of
  // its peak), widened by 4 pulse sigma; every entry resampled onto it (the same bins where the
  // varied keys leave the geometry alone).
  const std::vector<double>& axis = results[0].height_m;
  std::size_t first = axis.size(), last = 0;
  for (const EntryResult& r : results) {
    for (const auto& w : r.waveform_W) {
      const std::vector<double> on_axis = resample(w, r.height_m, axis);
      const double peak = *std::max_element(on_axis.begin(), on_axis.end());
      for (std::size_t b = 0; b < on_axis.size(); ++b) {
        if (!(on_axis[b] > 1e-6 * peak)) continue;
        first = std::min(first, b);
        last = std::max(last, b);
      }
    }
  }
  if (first > last) throw run_error("/table", "no entry of the table has any return");
  const std::size_t margin =
      static_cast<std::size_t>(std::ceil(4.0 * table.pulse_sigma_ns / table.bin_ns));
  first = first > margin ? first - margin : 0;
  last = std::min(axis.size() - 1, last + margin);
  table.height_m.assign(axis.begin() + first, axis.begin() + last + 1);
  table.off_nadir_deg = results[0].off_nadir_deg;

  std::vector<double> relative;
  for (EntryResult& r : results) {
    std::vector<std::vector<double>> waveforms;
    for (const auto& w : r.waveform_W) waveforms.push_back(resample(w, r.height_m, table.height_m));
    for (std::size_t band = 0; band < waveforms.size(); ++band) {
      const double peak = *std::max_element(waveforms[band].begin(), waveforms[band].end());
      if (peak > 0.0 && std::isfinite(r.mc_sd_W[band])) relative.push_back(r.mc_sd_W[band] / peak);
    }
    table.waveform_W.push_back(std::move(waveforms));
    if (!r.shot0_W.empty()) {
      std::vector<std::vector<double>> shot0;
      for (const auto& w : r.shot0_W) shot0.push_back(resample(w, r.height_m, table.height_m));
      table.shot0_W.push_back(std::move(shot0));
    }
    table.mc_sd_W.push_back(r.mc_sd_W);
    table.pai_true.push_back(r.pai);
    table.cover_true.push_back(r.cover);
    table.canopy_height_true_m.push_back(r.height);
    table.pgap_true.push_back(r.pgap);
    table.energy_canopy_J.push_back(r.energy_canopy_J);
    table.energy_ground_J.push_back(r.energy_ground_J);
    table.rhov_rhog.push_back(
        implied_rhov_rhog(r.energy_canopy_J.at(0), r.energy_ground_J.at(0), r.cover));
  }
  table.mc_relative_sd = kNaN;
  if (!relative.empty()) {
    std::nth_element(relative.begin(), relative.begin() + relative.size() / 2, relative.end());
    table.mc_relative_sd = relative[relative.size() / 2];
  }
  return table;
}

// ---- the file --------------------------------------------------------------------------------

namespace {

std::string parameter_variable(const TableParameter& p) {
  std::string name = "param_" + p.key;
  std::replace(name.begin(), name.end(), '.', '_');
  return name;
}

std::string joined(const std::vector<std::string>& texts) {
  std::string out;
  for (const std::string& t : texts) out += (out.empty() ? "" : ",") + t;
  return out;
}

std::vector<std::string> split(const std::string& text) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = text.find(',', start);
    out.push_back(
        text.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

}  // namespace

void write_table(const ForwardTable& table, const std::filesystem::path& path,
                 const std::string& command_line) {
  NetcdfFile nc = NetcdfFile::create(path);
  const std::size_t entries = table.entries(), bands = table.bands(), bins = table.height_m.size();
  nc.define_dimension("entry", entries);
  nc.define_dimension("band", bands);
  nc.define_dimension("height", bins);
  nc.put_text("", "Conventions", "CF-1.10");
  nc.put_text("", "title", "glaswave forward table for the rt retrieval");
  nc.put_text("", "glaswave_table_version", "2");
  nc.put_text("", "source", std::string("glaswave ") + GLASWAVE_VERSION);
  nc.put_text("", "history", command_line);
  nc.put_text("", "config", table.config_json);
  nc.put_text("", "design", "Halton, Cranley-Patterson rotated by the configuration's seed");
  nc.put_number("", "seed", static_cast<double>(table.seed));
  nc.put_number("", "bin_ns", table.bin_ns);
  nc.put_number("", "pulse_sigma_ns", table.pulse_sigma_ns);
  nc.put_number("", "off_nadir_deg", table.off_nadir_deg);
  nc.put_number("", "shots_per_entry", static_cast<double>(table.shots_per_entry));
  nc.put_number("", "rays_per_shot", static_cast<double>(table.rays_per_shot));
  nc.put_number("", "mc_relative_sd", table.mc_relative_sd);
  nc.define_variable("band_name", NC_STRING, {"band"}, "", "name of the band");
  nc.define_variable("height", NC_DOUBLE, {"height"}, "m",
                     "bin centre height above the footprint's ground");
  nc.put_text("height", "positive", "up");
  for (const TableParameter& p : table.parameters) {
    const std::string name = parameter_variable(p);
    nc.define_variable(
        name, NC_DOUBLE, {"entry"}, "",
        p.is_range() ? "value of " + p.key : "index of the value of " + p.key + " in `values`");
    nc.put_text(name, "key", p.key);
    if (p.is_range()) {
      nc.put_number(name, "valid_min", p.low);
      nc.put_number(name, "valid_max", p.high);
    } else {
      nc.put_text(name, "values", json(p.values).dump());
    }
  }
  nc.put_text("", "parameters", [&] {
    std::vector<std::string> keys;
    for (const TableParameter& p : table.parameters) keys.push_back(p.key);
    return joined(keys);
  }());
  nc.define_variable("waveform", NC_DOUBLE, {"entry", "band", "height"}, "W",
                     "mean received power of the entry's shots");
  const bool shot0 = table.shot0_W.size() == entries;
  if (shot0)
    nc.define_variable("waveform_shot0", NC_DOUBLE, {"entry", "band", "height"}, "W",
                       "received power of the entry's first shot alone");
  nc.define_variable("waveform_mc_sd", NC_DOUBLE, {"entry", "band"}, "W",
                     "one shot's Monte Carlo sd per bin over the bins holding signal");
  nc.define_variable("energy_canopy", NC_DOUBLE, {"entry", "band"}, "J",
                     "energy last scattered by vegetation");
  nc.define_variable("energy_ground", NC_DOUBLE, {"entry", "band"}, "J",
                     "energy last scattered by the ground");
  nc.define_variable("pai_true", NC_DOUBLE, {"entry"}, "1", "plant area index under the beam");
  nc.define_variable("cover_true", NC_DOUBLE, {"entry"}, "1", "canopy cover under the beam");
  nc.define_variable("canopy_height_true", NC_DOUBLE, {"entry"}, "m", "canopy height");
  nc.define_variable("pgap_true", NC_DOUBLE, {"entry"}, "1",
                     "gap probability looking down vertically, under the beam");
  nc.define_variable("rhov_rhog", NC_DOUBLE, {"entry"}, "1",
                     "canopy-to-ground reflectance ratio the forest implies (first band)");
  nc.end_define();
  nc.write("band_name", table.band_names);
  nc.write("height", table.height_m);
  for (std::size_t p = 0; p < table.parameters.size(); ++p) {
    std::vector<double> values(entries);
    for (std::size_t e = 0; e < entries; ++e) values[e] = table.parameter_values[e][p];
    nc.write(parameter_variable(table.parameters[p]), values);
  }
  std::vector<double> waveform, first, mc, canopy, ground;
  for (std::size_t e = 0; e < entries; ++e) {
    for (std::size_t band = 0; band < bands; ++band) {
      waveform.insert(waveform.end(), table.waveform_W[e][band].begin(),
                      table.waveform_W[e][band].end());
      if (shot0)
        first.insert(first.end(), table.shot0_W[e][band].begin(), table.shot0_W[e][band].end());
      mc.push_back(table.mc_sd_W[e][band]);
      canopy.push_back(table.energy_canopy_J[e][band]);
      ground.push_back(table.energy_ground_J[e][band]);
    }
  }
  nc.write("waveform", waveform);
  if (shot0) nc.write("waveform_shot0", first);
  nc.write("waveform_mc_sd", mc);
  nc.write("energy_canopy", canopy);
  nc.write("energy_ground", ground);
  nc.write("pai_true", table.pai_true);
  nc.write("cover_true", table.cover_true);
  nc.write("canopy_height_true", table.canopy_height_true_m);
  // A table made in memory without its gap probabilities leaves the fill, NaN.
  if (table.pgap_true.size() == entries) nc.write("pgap_true", table.pgap_true);
  nc.write("rhov_rhog", table.rhov_rhog);
  nc.commit();
}

ForwardTable read_table(const std::filesystem::path& path) {
  const NetcdfFile nc = NetcdfFile::open(path);
  const auto fail = [&](const std::string& why) -> void { throw input_error(path.string(), why); };
  if (!nc.text_attribute("", "glaswave_table_version"))
    fail(
        "not a glaswave forward table (no glaswave_table_version attribute; made by `glaswave "
        "table`)");
  ForwardTable table;
  const auto number = [&](const char* name) {
    const std::optional<double> v = nc.number_attribute("", name);
    if (!v) fail(std::string("no attribute `") + name + "`");
    return *v;
  };
  table.bin_ns = number("bin_ns");
  table.pulse_sigma_ns = number("pulse_sigma_ns");
  table.off_nadir_deg = number("off_nadir_deg");
  table.shots_per_entry = static_cast<std::int64_t>(number("shots_per_entry"));
  table.rays_per_shot = static_cast<std::int64_t>(number("rays_per_shot"));
  table.mc_relative_sd = number("mc_relative_sd");
  table.seed = static_cast<std::uint64_t>(number("seed"));
  table.config_json = nc.text_attribute("", "config").value_or("");
  table.band_names = nc.strings("band_name");
  table.height_m = nc.doubles("height");
  const std::vector<std::size_t> shape = nc.shape("waveform");
  if (shape.size() != 3 || shape[1] != table.band_names.size() || shape[2] != table.height_m.size())
    fail("`waveform` must be (entry, band, height)");
  const std::size_t entries = shape[0], bands = shape[1], bins = shape[2];
  if (entries == 0 || bins < 2) fail("the table is empty");
  const std::vector<double> waveform = nc.doubles("waveform");
  std::vector<double> first;
  if (nc.has_variable("waveform_shot0")) {
    if (nc.shape("waveform_shot0") != shape) fail("`waveform_shot0` must be shaped as `waveform`");
    first = nc.doubles("waveform_shot0");
  }
  const std::vector<double> mc = nc.doubles("waveform_mc_sd");
  const std::vector<double> canopy = nc.doubles("energy_canopy");
  const std::vector<double> ground = nc.doubles("energy_ground");
  if (mc.size() != entries * bands || canopy.size() != entries * bands ||
      ground.size() != entries * bands)
    fail("the per-band variables must be (entry, band)");
  for (std::size_t e = 0; e < entries; ++e) {
    std::vector<std::vector<double>> w(bands);
    std::vector<double> m, c, g;
    for (std::size_t band = 0; band < bands; ++band) {
      const auto begin = waveform.begin() + static_cast<std::ptrdiff_t>((e * bands + band) * bins);
      w[band].assign(begin, begin + static_cast<std::ptrdiff_t>(bins));
      for (double& x : w[band])
        if (!std::isfinite(x)) fail("`waveform` holds a value that is not finite");
      m.push_back(mc[e * bands + band]);
      c.push_back(canopy[e * bands + band]);
      g.push_back(ground[e * bands + band]);
    }
    table.waveform_W.push_back(std::move(w));
    if (!first.empty()) {
      std::vector<std::vector<double>> w0(bands);
      for (std::size_t band = 0; band < bands; ++band) {
        const auto begin = first.begin() + static_cast<std::ptrdiff_t>((e * bands + band) * bins);
        w0[band].assign(begin, begin + static_cast<std::ptrdiff_t>(bins));
        for (double& x : w0[band])
          if (!std::isfinite(x)) fail("`waveform_shot0` holds a value that is not finite");
      }
      table.shot0_W.push_back(std::move(w0));
    }
    table.mc_sd_W.push_back(std::move(m));
    table.energy_canopy_J.push_back(std::move(c));
    table.energy_ground_J.push_back(std::move(g));
  }
  const auto per_entry = [&](const char* name) {
    std::vector<double> v = nc.doubles(name);
    if (v.size() != entries) fail(std::string("`") + name + "` must be (entry)");
    return v;
  };
  table.pai_true = per_entry("pai_true");
  table.cover_true = per_entry("cover_true");
  table.canopy_height_true_m = per_entry("canopy_height_true");
  // Tables made before the gap probability was measured hold none: NaN, which rt reports.
  table.pgap_true =
      nc.has_variable("pgap_true") ? per_entry("pgap_true") : std::vector<double>(entries, kNaN);
  table.rhov_rhog = per_entry("rhov_rhog");
  const std::optional<std::string> keys = nc.text_attribute("", "parameters");
  if (!keys) fail("no attribute `parameters`");
  table.parameter_values.assign(entries, {});
  for (const std::string& key : split(*keys)) {
    TableParameter p{key, 0.0, 0.0, {}};
    const std::string name = parameter_variable(p);
    if (const std::optional<std::string> values = nc.text_attribute(name, "values")) {
      try {
        p.values = json::parse(*values).get<std::vector<std::string>>();
      } catch (const json::exception&) {
        fail("`" + name + "`'s values are not a JSON array of strings");
      }
    } else {
      p.low = nc.number_attribute(name, "valid_min").value_or(kNaN);
      p.high = nc.number_attribute(name, "valid_max").value_or(kNaN);
    }
    const std::vector<double> v = per_entry(name.c_str());
    for (std::size_t e = 0; e < entries; ++e) table.parameter_values[e].push_back(v[e]);
    table.parameters.push_back(std::move(p));
  }
  return table;
}

}  // namespace glaswave
