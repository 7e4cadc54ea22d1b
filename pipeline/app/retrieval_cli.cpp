// `glaswave table` and `glaswave retrieve`: their options, the summary they print.
#include "pipeline/app/retrieval_cli.hpp"

#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <optional>

#include "core/error.hpp"
#include "core/excerpt.hpp"
#include "pipeline/app/plots.hpp"
#include "pipeline/config/config.hpp"
#include "pipeline/retrieval/forward_table.hpp"
#include "pipeline/retrieval/retrieve.hpp"

namespace glaswave {

namespace {

std::optional<std::int64_t> decimal(const std::string& text, const char* option,
                                    const std::string& usage) {
  if (text.empty()) return std::nullopt;
  std::int64_t value = -1;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.find_first_not_of("0123456789") != std::string::npos || error != std::errc() ||
      end != text.data() + text.size())
    throw config_error(option, usage);
  return value;
}

int threads_of(const std::string& text) {
  if (text.empty()) return 0;
  const auto value =
      decimal(text, "--threads", "must be an integer in [0, 65536], got " + quoted_excerpt(text));
  if (*value > 65536)
    throw config_error("--threads", "must be an integer in [0, 65536], got " + excerpt(text));
  return static_cast<int>(*value);
}

// --counts-per-watt, --photons-per-joule: a positive finite number, all of the text.
std::optional<double> scale_of(const std::string& text, const std::string& option,
                               const std::string& unit) {
  if (text.empty()) return std::nullopt;
  double value = 0.0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size() || !(value > 0.0) ||
      !std::isfinite(value))
    throw config_error(option,
                       "must be a positive number of " + unit + ", got " + quoted_excerpt(text));
  return value;
}

// The comma-separated parts of `text` (one empty part for an empty text).
std::vector<std::string> comma_parts(const std::string& text) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = text.find(',', start);
    parts.push_back(text.substr(start, comma == std::string::npos ? comma : comma - start));
    if (comma == std::string::npos) return parts;
    start = comma + 1;
  }
}

// --beams: GEDI's group names (BEAM0101) or beam numbers (5).
std::vector<int> beams_of(const std::string& text) {
  std::vector<int> beams;
  if (text.empty()) return beams;
  const std::string usage = "expected beams as BEAM0101 or 5, comma-separated, got ";
  for (const std::string& part : comma_parts(text)) {
    int beam = 0;
    if (part.size() == 8 && part.rfind("BEAM", 0) == 0 &&
        part.find_first_not_of("01", 4) == std::string::npos) {
      for (char c : part.substr(4)) beam = beam * 2 + (c == '1');
    } else {
      const std::optional<std::int64_t> number =
          decimal(part, "--beams", usage + quoted_excerpt(part));
      if (!number || *number > 65535) throw config_error("--beams", usage + quoted_excerpt(part));
      beam = static_cast<int>(*number);
    }
    beams.push_back(beam);
  }
  return beams;
}

// --bbox W,S,E,N in degrees: longitudes in [-180, 180] (W > E crosses the antimeridian),
// latitudes in [-90, 90] with S <= N.
std::optional<std::array<double, 4>> bbox_of(const std::string& text) {
  if (text.empty()) return std::nullopt;
  const std::string usage =
      "expected W,S,E,N in degrees (longitudes -180 to 180, latitudes -90 to 90, S <= N), got " +
      quoted_excerpt(text);
  const std::vector<std::string> parts = comma_parts(text);
  if (parts.size() != 4) throw config_error("--bbox", usage);
  std::array<double, 4> box{};
  for (std::size_t i = 0; i < 4; ++i) {
    const auto [end, error] =
        std::from_chars(parts[i].data(), parts[i].data() + parts[i].size(), box[i]);
    if (parts[i].empty() || error != std::errc() || end != parts[i].data() + parts[i].size() ||
        !std::isfinite(box[i]))
      throw config_error("--bbox", usage);
  }
  const auto [west, south, east, north] = box;
  if (std::abs(west) > 180.0 || std::abs(east) > 180.0 || std::abs(south) > 90.0 ||
      std::abs(north) > 90.0 || south > north)
    throw config_error("--bbox", usage);
  return box;
}

}  // namespace

RetrievalCommands::RetrievalCommands(CLI::App& app) {
  table_ = app.add_subcommand("table", "simulate the forward table the `rt` retrieval searches");
  table_->footer(
      "Example:\n"
      "  glaswave table share/studies/retrieval_table.json --out gedi_table.nc\n"
      "The configuration's `table` section names the varied keys and the entries. Exit status: "
      "0 done, 2 bad command line or configuration, 3 unusable input data, 4 failure while "
      "running. Manual: docs/retrieval.md.");
  table_->add_option("CONFIG", config_file, "the configuration, with its `table` section")
      ->type_name("CONFIG.json")
      ->required();
  table_->add_option("--out", out, "the table to write (NetCDF)")
      ->type_name("TABLE.nc")
      ->required();
  table_->add_option("--set", overrides, "override a configuration key, as `run --set`")
      ->type_name("KEY=VALUE");
  table_->add_option("--threads", threads_text, "threads; 0 (the default) uses every core")
      ->type_name("N");
  table_->add_flag("--quiet", quiet, "no progress bar");

  retrieve_ = app.add_subcommand(
      "retrieve", "canopy height, cover, PAI and ground from measured shots, by every method");
  retrieve_->footer(
      "Example:\n"
      "  glaswave retrieve out/pass/shots.nc --table gedi_table.nc --out out/pass-retrieval\n"
      "  glaswave retrieve GEDI01_B_...h5 GEDI02_A_...h5 --out gedi-retrieval\n"
      "  glaswave retrieve GLAH01_...H5 GLAH14_...H5 --out glas-retrieval\n"
      "  glaswave retrieve ATL08_...h5 --out icesat2-retrieval\n"
      "  glaswave retrieve atl03.h5 atl08.h5 --table atlas-table.nc --out icesat2-rt\n"
      "Writes DIR/retrieval.nc: per shot and method, canopy_height, cover, pai, "
      "ground_elevation, rhov_rhog and pgap, rt's posterior sd and 5-95 % bounds and rt_flag, "
      "and the "
      "truth of simulated input; for GEDI L1B input also DIR/gedi_l2b.h5 in GEDI02_B's layout. "
      "Exit status as `run`. Manual: docs/retrieval.md.");
  retrieve_
      ->add_option(
          "INPUT", inputs,
          "glaswave's shots.nc, a GEDI L1B granule (GEDI01_B or gedi_l1b.h5) with "
          "its L2A beside it when given, a GLAS GLAH01 granule with its GLAH14, or an "
          "ICESat-2 ATL08 granule with its ATL03 beside it when given; the kind read from the "
          "layout")
      ->type_name("INPUT")
      ->required();
  retrieve_->add_option("--out", out, "output directory (default: the first input's)")
      ->type_name("DIR");
  retrieve_->add_option("--table", table_file, "the forward table (`glaswave table`), for rt")
      ->type_name("TABLE.nc");
  retrieve_
      ->add_option("--methods", methods,
                   "methods, comma-separated, among gedi_l2a, gedi_l2b, wi, rt for waveforms, "
                   "atl08, photon_ratio, rt for ATL08's segments (rt with ATL03's photons "
                   "beside; default: every one the input allows; rt with --table)")
      ->type_name("NAME,...");
  retrieve_->add_option("--shots", shots, "shot numbers A to B-1 only")->type_name("A:B");
  retrieve_->add_option("--beams", beams, "these beams only (BEAM0101 or 5, comma-separated)")
      ->type_name("B,...");
  retrieve_
      ->add_option("--bbox", bbox,
                   "shots inside this box only, degrees (west > east crosses the antimeridian)")
      ->type_name("W,S,E,N");
  retrieve_
      ->add_option("--rt-search", rt_search,
                   "rt's search: projected (the default: principal components pick the entries "
                   "that get the exact likelihood), two_stage (the exact likelihood of every "
                   "entry) or direct (every entry at every bin about L2A's ground)")
      ->type_name("NAME");
  retrieve_
      ->add_option("--counts-per-watt", counts_per_watt,
                   "a granule's digitiser counts per watt of received power, which rt needs to "
                   "compare its waveforms with the table's: glaswave's granules carry it, a real "
                   "granule does not")
      ->type_name("X");
  retrieve_
      ->add_option("--photons-per-joule", photons_per_joule,
                   "an ATL03 granule's detected photons per joule of the table's return (its "
                   "detection efficiency over a photon's energy, times the beam's share of the "
                   "pulse), which rt needs: glaswave's ATL03 carries it, a real one does not")
      ->type_name("X");
  retrieve_->add_option("--threads", threads_text, "threads; 0 (the default) uses every core")
      ->type_name("N");
  retrieve_->add_flag("--quiet", quiet, "no progress bar");
  retrieve_->add_flag("--json", json, "print the summary as one JSON object");
  retrieve_->add_flag("--plots", plots,
                      "also draw DIR/plots/: each method's estimates against the truth (or "
                      "against L2A's and L2B's for real input), and a few shots over rt's best "
                      "fits");
}

bool RetrievalCommands::chosen() const { return *table_ || *retrieve_; }

int RetrievalCommands::dispatch(const std::string& command_line, const ProgressFactory& progress) {
  return *table_ ? table(command_line, progress) : retrieve(command_line, progress);
}

int RetrievalCommands::table(const std::string& command_line, const ProgressFactory& progress) {
  const std::filesystem::path file(config_file);
  nlohmann::json document = read_json_file(file);
  for (const std::string& assignment : overrides) apply_override(document, assignment);
  TableRequest request{document, file.parent_path(), threads_of(threads_text)};
  if (std::filesystem::exists(out)) throw config_error(out, "exists already: give another --out");
  // Its folder is made as `run` makes its own, before the table is simulated.
  const std::filesystem::path folder = std::filesystem::path(out).parent_path();
  std::error_code made;
  if (!folder.empty()) std::filesystem::create_directories(folder, made);
  if (made)
    throw config_error(out, "cannot make its folder " + folder.string() + ": " + made.message());
  const auto started = std::chrono::steady_clock::now();
  const ForwardTable table = build_table(request, progress(quiet, "entries"));
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  write_table(table, out, command_line);
  std::printf(
      "glaswave: %zu entries in %.2f s (%.3g s an entry), %zu bins of %zu band(s); "
      "Monte Carlo sd %.3g of the peak; %s\n",
      table.entries(), wall_s, wall_s / static_cast<double>(table.entries()), table.height_m.size(),
      table.bands(), table.mc_relative_sd, out.c_str());
  return 0;
}

int RetrievalCommands::retrieve(const std::string& command_line, const ProgressFactory& progress) {
  RetrieveRequest request;
  for (const std::string& input : inputs) request.inputs.emplace_back(input);
  request.out_dir = out;
  if (!table_file.empty()) request.table = table_file;
  if (!methods.empty()) request.methods = comma_parts(methods);
  if (!shots.empty()) {
    const std::string usage = "expected A:B with shot numbers, got " + quoted_excerpt(shots);
    const auto colon = shots.find(':');
    if (colon == std::string::npos) throw config_error("--shots", usage);
    request.first_shot = decimal(shots.substr(0, colon), "--shots", usage);
    request.last_shot = decimal(shots.substr(colon + 1), "--shots", usage);
  }
  if (rt_search == "two_stage")
    request.rt.search = RtSearch::two_stage;
  else if (rt_search == "direct")
    request.rt.search = RtSearch::direct;
  else if (!rt_search.empty() && rt_search != "projected")
    throw config_error("--rt-search",
                       "expected projected, two_stage or direct, got " + quoted_excerpt(rt_search));
  request.counts_per_W = scale_of(counts_per_watt, "--counts-per-watt", "counts per watt");
  request.photons_per_J = scale_of(photons_per_joule, "--photons-per-joule", "photons per joule");
  request.beams = beams_of(beams);
  request.bbox_deg = bbox_of(bbox);
  request.threads = threads_of(threads_text);
  request.command_line = command_line;
  const RetrieveSummary summary = run_retrieval(request, progress(quiet || json, "shots"));
  // As `run` draws its plots: a plot that fails leaves the products complete and warns.
  std::string plot_warning;
  if (plots)
    plot_warning = plots_after_products(summary.product.parent_path(), "plot_retrieval.py");
  const double rate = summary.wall_s > 0.0 ? summary.shots / summary.wall_s : 0.0;
  std::string names;
  for (const std::string& m : summary.methods) names += (names.empty() ? "" : ",") + m;
  if (json) {
    nlohmann::json j = {{"shots", summary.shots},
                        {"methods", summary.methods},
                        {"rt_flagged", summary.rt_flagged},
                        {"wall_s", summary.wall_s},
                        {"shots_per_s", rate},
                        {"product", summary.product.string()}};
    if (!summary.l2b_granule.empty()) j["l2b_granule"] = summary.l2b_granule.string();
    if (std::isfinite(summary.rt_photon_tempering))
      j["rt_photon_tempering"] = summary.rt_photon_tempering;
    std::printf("%s\n", j.dump().c_str());
  } else {
    std::printf(
        "glaswave: %lld shots retrieved by %s in %.2f s (%.0f shots/s); %lld flagged by "
        "rt; %s\n",
        static_cast<long long>(summary.shots), names.c_str(), summary.wall_s, rate,
        static_cast<long long>(summary.rt_flagged), summary.product.c_str());
    if (!summary.l2b_granule.empty()) std::printf("glaswave: %s\n", summary.l2b_granule.c_str());
    if (std::isfinite(summary.rt_photon_tempering))
      std::printf("glaswave: rt's photon likelihood tempered by %.3g (calibrated on the table)\n",
                  summary.rt_photon_tempering);
  }
  if (!plot_warning.empty()) std::fprintf(stderr, "glaswave: warning: %s\n", plot_warning.c_str());
  return 0;
}

}  // namespace glaswave
