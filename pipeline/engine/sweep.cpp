// The sensitivity sweep: cases simulated in turn, their mean returns written as CSV and Markdown.
#include "pipeline/engine/sweep.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/excerpt.hpp"
#include "pipeline/engine/inputs.hpp"
#include "pipeline/engine/run.hpp"

namespace glaswave {
namespace {

struct CaseReturns {
  std::string key, value;          // empty key: the base case
  std::vector<double> tr, cr, gr;  // per band, mean over the track's good shots (J)
};

// `progress` is told (shots done, shots in all) for this case's track.
CaseReturns simulate_case(const SweepRequest& request, const std::string& key,
                          const std::string& value, const ProgressCallback& progress) {
  std::vector<std::string> overrides = request.overrides;
  if (!key.empty()) overrides.push_back(key + "=" + value);
  const Config config = load_config(request.config_file, overrides);
  const std::unique_ptr<Terrain> terrain = open_terrain(config);
  const std::unique_ptr<Track> planned = plan_track(config, *terrain);
  const Track& track = *planned;
  const std::unique_ptr<ShotSimulator> simulator = make_shot_simulator(config, *terrain);
  simulator->share_scenes_along(track);  // as a run does
  const std::size_t bands = config.sensor.bands.size();
  CaseReturns returns{key, value, std::vector<double>(bands, 0.0), std::vector<double>(bands, 0.0),
                      std::vector<double>(bands, 0.0)};
  std::vector<std::int64_t> counted(bands, 0);
  simulate_records(
      *simulator, track, 0, track.size(), request.threads,
      [&](std::int64_t, const ShotRecord& shot) {
        for (std::size_t b = 0; b < bands; ++b) {
          if (shot.quality_flag != quality_good || !std::isfinite(shot.energy_cr_J[b]) ||
              !std::isfinite(shot.energy_gr_J[b]))
            continue;
          returns.tr[b] += shot.energy_tr_J[b];
          returns.cr[b] += shot.energy_cr_J[b];
          returns.gr[b] += shot.energy_gr_J[b];
          ++counted[b];
        }
      },
      progress);
  for (std::size_t b = 0; b < bands; ++b) {
    const double n = counted[b] > 0 ? static_cast<double>(counted[b]) : std::nan("");
    returns.tr[b] /= n;
    returns.cr[b] /= n;
    returns.gr[b] /= n;
  }
  return returns;
}

// The % deviation from the base case, one decimal; signed as the seed's table is for `signed_`.
std::string percent(double value, double base, bool signed_ = false) {
  double change = 100.0 * (value / base - 1.0);
  if (std::abs(change) < 0.05) change = 0.0;  // no "-0.0"
  char text[32];
  std::snprintf(text, sizeof text, signed_ && change != 0.0 ? "%+.1f" : "%.1f", change);
  return text;
}

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", value);
  return text;
}

// A CSV field: quoted when it holds a comma or a quote.
std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

}  // namespace

Variation parse_variation(const std::string& text) {
  const auto equals = text.find('=');
  if (equals == std::string::npos || equals == 0)
    throw config_error("--vary", "expected KEY=V1,V2,..., got " + quoted_excerpt(text));
  Variation variation{text.substr(0, equals), {}};
  std::string value;
  int depth = 0;
  bool in_string = false;
  for (char c : text.substr(equals + 1)) {
    if (c == '"') in_string = !in_string;
    if (!in_string && (c == '[' || c == '{')) ++depth;
    if (!in_string && (c == ']' || c == '}')) --depth;
    if (c == ',' && depth == 0 && !in_string) {
      variation.values.push_back(value);
      value.clear();
    } else {
      value += c;
    }
  }
  variation.values.push_back(value);
  for (const std::string& v : variation.values)
    if (v.empty()) throw config_error("--vary", "an empty value in " + quoted_excerpt(text));
  return variation;
}

namespace {

// sensitivity.csv: one row per case and band, deviations from the base case in percent.
std::string sensitivity_csv(const std::vector<LidarBand>& bands, const CaseReturns& base,
                            const std::vector<CaseReturns>& cases) {
  std::ostringstream csv;
  csv << "key,value,band,tr,cr,gr,tr_pct,cr_pct,gr_pct\n";
  for (std::size_t b = 0; b < bands.size(); ++b)
    csv << "base,," << csv_field(bands[b].name) << ',' << number(base.tr[b]) << ','
        << number(base.cr[b]) << ',' << number(base.gr[b]) << ",,,\n";
  for (const CaseReturns& c : cases)
    for (std::size_t b = 0; b < bands.size(); ++b)
      csv << csv_field(c.key) << ',' << csv_field(c.value) << ',' << csv_field(bands[b].name) << ','
          << number(c.tr[b]) << ',' << number(c.cr[b]) << ',' << number(c.gr[b]) << ','
          << percent(c.tr[b], base.tr[b]) << ',' << percent(c.cr[b], base.cr[b]) << ','
          << percent(c.gr[b], base.gr[b]) << '\n';
  return csv.str();
}

// sensitivity.md: the seed's Table 3, per band, each key's values with the base case's own
// value as "-".
std::string sensitivity_markdown(const Config& base_config,
                                 const std::vector<Variation>& variations, const CaseReturns& base,
                                 const std::vector<CaseReturns>& cases) {
  const std::vector<LidarBand>& bands = base_config.sensor.bands;
  std::ostringstream md;
  for (std::size_t b = 0; b < bands.size(); ++b) {
    md << "## Band " << bands[b].name << "\n\n"
       << "Variation from the base case, mean over the track's shots; returns partitioned by "
          "position in the waveform.\n\n"
       << "| Parameter | Value | TR (%) | CR (%) | GR (%) |\n|---|---|---|---|---|\n";
    for (const Variation& variation : variations) {
      std::string path = variation.key;
      std::replace(path.begin(), path.end(), '.', '/');
      path.insert(path.begin(), '/');
      const nlohmann::json::json_pointer pointer(path);
      const std::string base_value =
          base_config.resolved.contains(pointer) ? base_config.resolved.at(pointer).dump() : "base";
      bool first_row = true;
      auto row = [&](const std::string& value, const std::string& tr, const std::string& cr,
                     const std::string& gr) {
        md << "| " << (first_row ? variation.key : "") << " | " << value << " | " << tr << " | "
           << cr << " | " << gr << " |\n";
        first_row = false;
      };
      row(base_value + " (base)", "-", "-", "-");
      for (const CaseReturns& c : cases)
        if (c.key == variation.key)
          row(c.value, percent(c.tr[b], base.tr[b], true), percent(c.cr[b], base.cr[b], true),
              percent(c.gr[b], base.gr[b], true));
    }
    md << "\n";
  }
  return md.str();
}

}  // namespace

void run_sweep(const SweepRequest& request, const ProgressCallback& progress) {
  if (request.variations.empty()) throw config_error("--vary", "give at least one KEY=V1,V2,...");
  // Every case is checked before any is simulated: a typo in the last value costs nothing.
  const Config base_config = load_config(request.config_file, request.overrides);
  for (const Variation& variation : request.variations)
    for (const std::string& value : variation.values) {
      std::vector<std::string> overrides = request.overrides;
      overrides.push_back(variation.key + "=" + value);
      load_config(request.config_file, overrides);
    }

  OutputDirectory directory(request.out_dir);
  // Progress over every case, each counted as many shots as the one running.
  std::int64_t case_count = 1, case_index = 0;
  for (const Variation& variation : request.variations)
    case_count += static_cast<std::int64_t>(variation.values.size());
  auto case_progress = [&](std::int64_t done, std::int64_t total) {
    if (progress) progress(case_index * total + done, case_count * total);
  };
  const CaseReturns base = simulate_case(request, "", "", case_progress);
  std::vector<CaseReturns> cases;
  for (const Variation& variation : request.variations)
    for (const std::string& value : variation.values) {
      ++case_index;
      cases.push_back(simulate_case(request, variation.key, value, case_progress));
    }

  write_text_atomically(request.out_dir / "sensitivity.csv",
                        sensitivity_csv(base_config.sensor.bands, base, cases));
  write_text_atomically(request.out_dir / "sensitivity.md",
                        sensitivity_markdown(base_config, request.variations, base, cases));
  directory.keep();
}

}  // namespace glaswave
