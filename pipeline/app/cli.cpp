// Command line: run, sweep, brf, check, voxelize, table, retrieve, --help, --version.
#include "pipeline/app/cli.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <limits>
#include <new>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string_view>
#include <tuple>

#include "canopy/gap_fraction.hpp"
#include "core/error.hpp"
#include "core/excerpt.hpp"
#include "core/input_file.hpp"
#include "pipeline/app/plots.hpp"
#include "pipeline/app/reference.hpp"
#include "pipeline/app/retrieval_cli.hpp"
#include "pipeline/app/run_outline.hpp"
#include "pipeline/config/keys.hpp"
#include "pipeline/engine/brf.hpp"
#include "pipeline/engine/cluster.hpp"
#include "pipeline/engine/ray_debug.hpp"
#include "pipeline/engine/run.hpp"
#include "pipeline/engine/sweep.hpp"

namespace glaswave {
namespace {

struct Arguments {
  std::string config_file;
  std::string out_dir;
  std::vector<std::string> overrides;
  int threads = 0;
  std::string threads_text;
  std::string shots;
  std::string seed_text;
  std::optional<std::uint64_t> seed;
  bool resume = false;
  bool quiet = false;
  double progress_interval_s = 5.0;  // a progress line on a non-terminal (hidden option, tests)
  bool json = false;                 // run --json: the summary as one JSON object
  std::string debug_ray;             // SHOT:RAY
  bool schema = false;               // check --schema
  bool keys_markdown = false;        // check --keys-markdown (hidden: scripts/docs-reference)
  bool fields_json = false;          // check --fields-json (hidden: scripts/docs-reference)
  std::string cloud_file;            // voxelize CLOUD.las
  double voxel_size_m = 1.0;         // voxelize --voxel-size-m
  std::string crs;                   // voxelize --crs
  bool force = false;                // voxelize --force: write over an existing grid
};

// A decimal integer of an option, in [0, max]: digits only (CLI11 would take "0x10" as 16, an
// empty text as the default, and saturate beyond 2^64 - 1).
std::uint64_t decimal_option(const std::string& text, const char* option, std::uint64_t max) {
  const std::string range = "must be an integer in [0, " + std::to_string(max) + "]";
  std::uint64_t value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  const bool digits = !text.empty() && text.find_first_not_of("0123456789") == std::string::npos;
  if (!digits) throw config_error(option, range + ", got " + quoted_excerpt(text));
  // Digits alone are an integer: beyond the range it is too large.
  if (error != std::errc() || end != text.data() + text.size() || value > max)
    throw config_error(
        option, "is too large: must be <= " + std::to_string(max) + ", got " + excerpt(text));
  return value;
}

// The two sides of "A:B" as non-negative integers, either absent when empty; `usage` is the
// message when the text is not of that form.
std::pair<std::optional<std::int64_t>, std::optional<std::int64_t>> colon_pair(
    const std::string& text, const char* option, const std::string& usage) {
  const auto colon = text.find(':');
  if (colon == std::string::npos) throw config_error(option, usage);
  auto number = [&](const std::string& part) -> std::optional<std::int64_t> {
    if (part.empty()) return std::nullopt;
    if (part.find_first_not_of("0123456789") != std::string::npos)
      throw config_error(option, usage);
    std::int64_t value = -1;
    const auto [end, error] = std::from_chars(part.data(), part.data() + part.size(), value);
    if (error != std::errc() || end != part.data() + part.size() || value < 0)
      throw config_error(option, usage);
    return value;
  };
  return {number(text.substr(0, colon)), number(text.substr(colon + 1))};
}

// "A:B" -> [A, B); either side may be empty.
void parse_shot_range(const std::string& text, RunRequest& request) {
  std::tie(request.first_shot, request.last_shot) =
      colon_pair(text, "--shots", "expected A:B with shot numbers, got " + quoted_excerpt(text));
}

// "SHOT:RAY" -> the two numbers, both needed.
std::pair<std::int64_t, std::int64_t> parse_shot_and_ray(const std::string& text) {
  const std::string usage =
      "expected SHOT:RAY, a shot number and a ray number, got " + quoted_excerpt(text);
  const auto [shot, ray] = colon_pair(text, "--debug-ray", usage);
  if (!shot || !ray) throw config_error("--debug-ray", usage);
  return {*shot, *ray};
}

Config load(const Arguments& arguments) {
  std::vector<std::string> overrides = arguments.overrides;
  if (arguments.seed) overrides.push_back("seed=" + std::to_string(*arguments.seed));
  return load_config(arguments.config_file, overrides);
}

// The command line for the products' history; without --resume, so that a resumed run's
// products are those of the run it finishes.
std::string joined(int argc, char** argv) {
  std::ostringstream line;
  for (int i = 0; i < argc; ++i)
    if (std::string_view(argv[i]) != "--resume") line << (i ? " " : "") << argv[i];
  return line.str();
}

// Progress on stderr, shots (or photons) done, per second, time left: a bar redrawn in place
// on a terminal; elsewhere (a log file, a batch job) a plain line every `interval_s`, without
// escape codes or carriage returns.
class Progress {
 public:
  Progress(bool enabled, double interval_s, const char* unit = "shots")
      : enabled_(enabled),
        terminal_(isatty(STDERR_FILENO) != 0),
        interval_s_(interval_s),
        unit_(unit),
        started_(now()),
        last_line_(started_) {}
  ~Progress() {
    if (drawn_) std::fprintf(stderr, "\n");
  }
  void operator()(std::int64_t done, std::int64_t total) {
    if (!enabled_) return;
    const double time = now();
    const double elapsed_s = time - started_;
    const double rate = elapsed_s > 0.0 ? done / elapsed_s : 0.0;
    const double left_s = rate > 0.0 ? (total - done) / rate : 0.0;
    if (!terminal_) {
      if (time - last_line_ < interval_s_ || done >= total) return;
      last_line_ = time;
      std::fprintf(stderr, "glaswave: %lld/%lld %s, %.1f %s/s, %.0f s left\n",
                   static_cast<long long>(done), static_cast<long long>(total), unit_, rate, unit_,
                   left_s);
      std::fflush(stderr);
      return;
    }
    constexpr int width = 30;
    const int filled = static_cast<int>(width * done / std::max<std::int64_t>(total, 1));
    std::fprintf(stderr, "\r[%s%s] %lld/%lld %s  %.1f %s/s  %.0f s left ",
                 std::string(filled, '#').c_str(), std::string(width - filled, '.').c_str(),
                 static_cast<long long>(done), static_cast<long long>(total), unit_, rate, unit_,
                 left_s);
    std::fflush(stderr);
    drawn_ = true;
  }

 private:
  static double now() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
        .count();
  }
  bool enabled_;
  bool terminal_;
  double interval_s_;
  const char* unit_;
  bool drawn_ = false;
  double started_;
  double last_line_;
};

// An element as --debug-ray prints it, in one word: ground, trunk/foliage=K,
// leaf/crown=N/foliage=K (N: the crown's index among the shot's crowns), leaf/layer/foliage=K.
std::string element_word(const RayEvent& event) {
  std::string word = to_string(event.element);
  if (event.element == RayElement::leaf)
    word += event.crown >= 0 ? "/crown=" + std::to_string(event.crown) : std::string("/layer");
  if (event.foliage >= 0) word += "/foliage=" + std::to_string(event.foliage);
  return word;
}

// Warnings go to stderr, one line each, as errors do.
void print_warnings(const std::vector<std::string>& warnings) {
  for (const std::string& warning : warnings)
    std::fprintf(stderr, "glaswave: warning: %s\n", escape_controls(warning).c_str());
}

// --debug-ray SHOT:RAY: one line per event on stdout, columns as docs/guide/command-line.md
// describes them.
int debug_ray_command(const Arguments& arguments) {
  const auto [shot, ray] = parse_shot_and_ray(arguments.debug_ray);
  const Config config = load(arguments);
  std::printf("# glaswave --debug-ray %lld:%lld: ray %lld of shot %lld, re-run alone as in a run\n",
              static_cast<long long>(shot), static_cast<long long>(ray),
              static_cast<long long>(ray), static_cast<long long>(shot));
  std::printf("%-6s %-11s %5s %12s %12s %12s %-24s", "path", "event", "order", "east_m", "north_m",
              "up_m", "element");
  for (const LidarBand& band : config.sensor.bands)
    std::printf(" %14s", ("weight_" + band.name).c_str());
  std::printf(" %16s %6s\n", "path_m", "bin");
  const RayDebug debug = debug_ray(config, shot, ray, [](const RayEvent& event) {
    std::printf("%-6s %-11s %5d %12.4f %12.4f %12.4f %-24s",
                event.single_scattering_path ? "single" : "multi", to_string(event.kind),
                event.order, event.position_m[0], event.position_m[1], event.position_m[2],
                element_word(event).c_str());
    for (double weight : event.weight) std::printf(" %14.6e", weight);
    const bool scored = event.kind == RayEventKind::score;
    const std::string bin = !scored               ? "-"
                            : event.tally_bin < 0 ? "outside"
                                                  : std::to_string(event.bin);
    std::printf(" %16.4f %6s\n", event.path_m, bin.c_str());
  });
  std::printf("# the ray's part of the shot's received energy (J):");
  for (std::size_t band = 0; band < debug.band_names.size(); ++band)
    std::printf(" %s %.6e", debug.band_names[band].c_str(), debug.waveforms.energy_J[band]);
  std::printf(" (of %lld rays)\n", static_cast<long long>(debug.rays_per_shot));
  return 0;
}

int run(const Arguments& arguments, const std::string& command_line) {
  if (!arguments.debug_ray.empty()) return debug_ray_command(arguments);
  // Under mpirun every process loads the configuration; a failure ends them all (one message).
  Cluster& cluster = Cluster::world();
  std::optional<Config> loaded;
  std::exception_ptr failure;
  try {
    loaded = load(arguments);
  } catch (...) {
    failure = std::current_exception();
  }
  cluster.agree(failure);
  const Config& config = *loaded;
  RunRequest request;
  request.resume = arguments.resume;
  request.threads = arguments.threads;
  request.command_line = command_line;
  request.out_dir =
      arguments.out_dir.empty()
          ? std::filesystem::path("out") / std::filesystem::path(arguments.config_file).stem()
          : std::filesystem::path(arguments.out_dir);
  if (!arguments.shots.empty()) parse_shot_range(arguments.shots, request);

  RunSummary summary;
  {
    Progress progress(!arguments.quiet && cluster.rank() == 0, arguments.progress_interval_s);
    summary = run_simulation(config, request, std::ref(progress));
  }
  if (cluster.rank() != 0) return 0;  // rank 0 reports
  print_warnings(summary.warnings);
  // Plots are drawn from the finished products; a failure there leaves them whole, a warning.
  if (config.output.plots) {
    if (const std::string warning = plots_after_products(request.out_dir); !warning.empty())
      print_warnings({warning});
  }
  const double wall_s = std::max(summary.wall_s, 1e-9);
  if (arguments.json) {
    const nlohmann::json object = {
        {"shots", summary.shots},
        {"shots_flagged", summary.shots_flagged},
        {"wall_s", summary.wall_s},
        {"shots_per_s", summary.shots / wall_s},
        {"ray_queries", summary.ray_queries},
        {"ray_queries_per_s", summary.ray_queries / wall_s},
        {"vertical_datum", summary.vertical_datum},
        {"out_dir", request.out_dir.string()},
    };
    std::printf("%s\n", object.dump().c_str());
    return 0;
  }
  // A resumed run's rate is that of the shots it simulated.
  const std::string resumed =
      summary.shots_resumed > 0
          ? " (" + std::to_string(summary.shots_resumed) + " kept from the interrupted run)"
          : std::string();
  std::printf(
      "glaswave: %lld shots%s in %.2f s, %.1f shots/s, %.3g ray queries/s, %lld flagged; %s; "
      "products in %s\n",
      static_cast<long long>(summary.shots), resumed.c_str(), summary.wall_s,
      (summary.shots - summary.shots_resumed) / wall_s, summary.ray_queries / wall_s,
      static_cast<long long>(summary.shots_flagged), summary.vertical_datum.c_str(),
      request.out_dir.string().c_str());
  return 0;
}

int check(const Arguments& arguments) {
  if (arguments.schema) {
    std::printf("%s\n", configuration_schema().dump(2).c_str());
    return 0;
  }
  if (arguments.keys_markdown) {
    std::printf("%s", configuration_keys_markdown().c_str());
    return 0;
  }
  if (arguments.fields_json) {
    std::printf("%s\n", product_fields_json().dump(2).c_str());
    return 0;
  }
  if (arguments.config_file.empty())
    throw config_error("check", "give CONFIG, or --schema for the configuration's JSON Schema");
  const Config config = load(arguments);
  const CheckSummary summary = check_inputs(config);
  print_warnings(summary.warnings);
  std::printf("glaswave: %s is valid: %lld shots, %s%lld off the terrain",
              arguments.config_file.c_str(), static_cast<long long>(summary.shots),
              summary.shots_located < summary.shots ? "about " : "",
              static_cast<long long>(summary.shots_off_terrain));
  if (summary.shots_located < summary.shots)
    std::printf(" (%lld of them located, evenly spread)",
                static_cast<long long>(summary.shots_located));
  // An orbit keeps only the shots on the terrain: say how many it skipped.
  if (summary.shots < summary.sequence_length)
    std::printf(" (%lld of the orbit's %lld shots fall on it)",
                static_cast<long long>(summary.shots),
                static_cast<long long>(summary.sequence_length));
  std::printf("\n");
  // Then what a run would do, for a person; the line above stays first, for scripts.
  std::printf("%s", run_outline(config, summary, arguments.config_file).c_str());
  return 0;
}

int sweep(const Arguments& arguments, const std::vector<std::string>& variations) {
  SweepRequest request;
  request.config_file = arguments.config_file;
  request.overrides = arguments.overrides;
  for (const std::string& text : variations) request.variations.push_back(parse_variation(text));
  request.out_dir =
      arguments.out_dir.empty()
          ? std::filesystem::path("out") /
                (std::filesystem::path(arguments.config_file).stem().string() + "-sweep")
          : std::filesystem::path(arguments.out_dir);
  request.threads = arguments.threads;
  {
    Progress progress(!arguments.quiet, arguments.progress_interval_s);
    run_sweep(request, std::ref(progress));
  }
  std::printf("glaswave: sensitivity.csv and sensitivity.md in %s\n",
              request.out_dir.string().c_str());
  return 0;
}

// brf: the sun's photons through the scene of the first footprint; brf.json and scene.tif.
int brf(const Arguments& arguments) {
  const Config config = load(arguments);
  BrfRequest request;
  request.threads = arguments.threads;
  request.out_dir =
      arguments.out_dir.empty()
          ? std::filesystem::path("out") /
                (std::filesystem::path(arguments.config_file).stem().string() + "-brf")
          : std::filesystem::path(arguments.out_dir);
  BrfSummary summary;
  {
    Progress bar(!arguments.quiet, arguments.progress_interval_s, "photons");
    summary = run_brf(config, request, std::ref(bar));
  }
  for (const auto& band : summary.document["bands"]) {
    std::printf("band %s: albedo %.4f", band["name"].get<std::string>().c_str(),
                band["albedo"].get<double>());
    for (const auto& view : band["views"])
      std::printf("; BRF(%g, %g) %.4f +- %.4f", view["zenith_deg"].get<double>(),
                  view["azimuth_deg"].get<double>(), view["brf"].get<double>(),
                  view["brf_stderr"].get<double>());
    std::printf("\n");
    if (!band.contains("toa_albedo")) continue;
    std::printf("band %s at the top of the atmosphere: albedo %.4f",
                band["name"].get<std::string>().c_str(), band["toa_albedo"].get<double>());
    for (const auto& view : band["views"])
      std::printf("; BRF(%g, %g) %.4f +- %.4f", view["zenith_deg"].get<double>(),
                  view["azimuth_deg"].get<double>(), view["toa_brf"].get<double>(),
                  view["toa_brf_stderr"].get<double>());
    std::printf("; sunlight reaching the scene: %.4f direct, %.4f diffuse\n",
                band["direct_transmittance"].get<double>(),
                band["diffuse_transmittance"].get<double>());
  }
  const double wall_s = std::max(summary.wall_s, 1e-9);
  std::printf(
      "glaswave: %lld photons in %.2f s, %.3g photons/s, %.3g ray queries/s; brf.json and "
      "scene.tif in %s\n",
      static_cast<long long>(summary.photons), summary.wall_s, summary.photons / wall_s,
      summary.ray_queries / wall_s, request.out_dir.string().c_str());
  return 0;
}

// voxelize: a LAS point cloud -> the voxel grid of plant area density (and the ground) that
// canopy.point_cloud would use, written in the `voxels` NetCDF format.
// voxelize's --out, before anything is computed: a new file in a folder that exists and takes
// it, or (with --force) a regular file to replace, never the cloud itself nor a directory or
// device.
void check_voxelize_out(const Arguments& arguments) {
  const std::string& out = arguments.out_dir;
  require_no_nul(out, "--out", ErrorKind::config);
  const std::string place = printable_path(out);
  const auto refuse = [&](const std::string& why) { throw config_error(place, why); };
  struct stat status {};
  if (::stat(out.c_str(), &status) == 0) {
    std::error_code error;
    if (std::filesystem::equivalent(out, arguments.cloud_file, error))
      refuse("--out is the point cloud itself; choose another --out");
    if (S_ISDIR(status.st_mode)) refuse("--out is a directory; give the grid file's name");
    if (!S_ISREG(status.st_mode)) refuse("--out exists and is not a regular file");
    if (!arguments.force)
      refuse("--out exists; remove it, choose another --out, or give --force to replace it");
  } else if (errno != ENOENT) {
    refuse(std::string("cannot use --out: ") + std::strerror(errno));
  }
  std::filesystem::path folder = std::filesystem::path(out).parent_path();
  if (folder.empty()) folder = ".";
  if (::stat(folder.c_str(), &status) != 0)
    refuse("--out's folder " + printable_path(folder.string()) +
           (errno == ENOENT ? " does not exist" : std::string(": ") + std::strerror(errno)));
  if (!S_ISDIR(status.st_mode))
    refuse("--out's folder " + printable_path(folder.string()) + " is not a folder");
  if (::access(folder.c_str(), W_OK | X_OK) != 0)
    refuse("cannot write in --out's folder " + printable_path(folder.string()) + ": " +
           std::strerror(errno));
}

int voxelize(const Arguments& arguments, const std::string& command_line) {
  if (!(arguments.voxel_size_m >= 0.05 && arguments.voxel_size_m <= 100.0))
    throw config_error("--voxel-size-m",
                       "must be in [0.05, 100] m, got " + std::to_string(arguments.voxel_size_m));
  check_voxelize_out(arguments);
  const LasFile cloud(arguments.cloud_file);
  GapFractionSettings settings;
  settings.voxel_size_m = arguments.voxel_size_m;
  const VoxelizeResult result = voxelize_point_cloud(cloud, arguments.crs, "--crs", settings);
  write_voxel_netcdf(arguments.out_dir, result.voxels, result.ground.height_m, command_line);
  const VoxelBlock& v = result.voxels;
  double pai = 0.0;
  for (int j = 0; j < v.ny; ++j)
    for (int i = 0; i < v.nx; ++i) pai += v.plant_area_index(i, j);
  const VoxelizeReport& r = result.report;
  std::printf(
      "glaswave: %llu points (%llu ground, %llu dropped as noise); %d x %d columns x %d layers "
      "of %g m, mean plant area index %.3f, %llu occluded layers; %s\n",
      static_cast<unsigned long long>(r.points), static_cast<unsigned long long>(r.ground_points),
      static_cast<unsigned long long>(r.noise_dropped), v.nx, v.ny, v.nz, settings.voxel_size_m,
      pai / std::max(1, v.nx * v.ny), static_cast<unsigned long long>(r.occluded_layers),
      arguments.out_dir.c_str());
  return 0;
}

// The command line's commands and the options they share, bound to one Arguments.
class Commands {
 public:
  Commands(CLI::App& app, Arguments& arguments) : app_(app), arguments_(arguments) {
    add_run();
    add_check();
    add_sweep();
    add_brf();
    add_voxelize();
    retrieval_ = std::make_unique<RetrievalCommands>(app_);
  }

  // Runs the command the line chose.
  int dispatch(const std::string& command_line) {
    read_given();
    if (Cluster::world().size() > 1 && (!*run_ || !arguments_.debug_ray.empty()))
      Cluster::world().agree(std::make_exception_ptr(
          config_error("mpirun",
                       "only `glaswave run` shares its shots among processes; run "
                       "this command without mpirun")));
    if (retrieval_->chosen())
      return retrieval_->dispatch(command_line, [&](bool quiet, const char* unit) {
        auto bar = std::make_shared<Progress>(!quiet, arguments_.progress_interval_s, unit);
        return [bar](std::int64_t done, std::int64_t total) { (*bar)(done, total); };
      });
    if (*brf_) return brf(arguments_);
    if (*voxelize_) return voxelize(arguments_, command_line);
    if (*run_) return run(arguments_, command_line);
    if (*sweep_) return sweep(arguments_, variations_);
    return check(arguments_);
  }

 private:
  void add_config(CLI::App* command, bool required) {
    auto* config = command->add_option("CONFIG", arguments_.config_file,
                                       "the configuration, a JSON file (see the manual's "
                                       "reference/configuration page, or `check --schema`)");
    config->type_name("CONFIG.json");
    if (required) config->required();
    command
        ->add_option("--set", arguments_.overrides,
                     "override a configuration key by its dotted path, e.g. --set canopy.pai=2 "
                     "(VALUE read as JSON when it parses, else as a string); repeatable")
        ->type_name("KEY=VALUE");
  }
  void add_threads(CLI::App* command) {
    given_.push_back(command
                         ->add_option("--threads", arguments_.threads_text,
                                      "threads to simulate on; 0 (the default) uses every core "
                                      "this process may use; results do not depend on it")
                         ->type_name("N"));
  }

  // Options given empty are refused rather than taken as absent; numbers are read as decimal.
  void read_given() {
    for (const CLI::Option* option : given_) {
      if (option->count() == 0) continue;
      const std::string name = option->get_name();
      for (const std::string& value : option->as<std::vector<std::string>>())
        if (value.empty()) throw config_error(name, "must not be empty");
      if (name == "--threads")
        arguments_.threads =
            static_cast<int>(decimal_option(arguments_.threads_text, "--threads", max_threads));
      if (name == "--seed")
        arguments_.seed = decimal_option(arguments_.seed_text, "--seed",
                                         std::numeric_limits<std::uint64_t>::max());
    }
  }

  void add_run() {
    run_ = app_.add_subcommand("run", "simulate the track's shots and write the products");
    run_->footer(
        "Examples:\n"
        "  glaswave run share/demo/demo.json --out out/demo\n"
        "  glaswave run pass.json --set canopy.pai=2 --shots 0:500 --out out/part1\n"
        "  mpirun -q -np 4 glaswave run pass.json --out out/pass   (shots shared among 4 "
        "processes)\n"
        "Prints one summary line at the end (--json: one JSON object). Exit status: 0 done, 2 bad "
        "command line or configuration, 3 unusable input data, 4 failure while running.\n"
        "Manual: docs/guide/command-line.md in the source (./scripts/docs builds the site); the "
        "keys: docs/reference/configuration.md.");
    add_config(run_, true);
    given_.push_back(run_->add_option("--out", arguments_.out_dir,
                                      "output directory, which must not exist (default "
                                      "out/<config name>)")
                         ->type_name("DIR"));
    add_threads(run_);
    given_.push_back(run_->add_option("--shots", arguments_.shots,
                                      "simulate shot numbers A to B-1 only, to split a track "
                                      "across jobs; either side may be empty")
                         ->type_name("A:B"));
    given_.push_back(run_->add_option("--seed", arguments_.seed_text,
                                      "random seed (overrides the configuration's `seed`)")
                         ->type_name("S"));
    run_->add_flag("--resume", arguments_.resume,
                   "finish a run that was killed, keeping the shots its journal holds");
    run_->add_flag("--quiet", arguments_.quiet, "no progress bar (nor progress lines)");
    run_->add_option("--progress-interval", arguments_.progress_interval_s)
        ->check(CLI::Range(0.0, 3600.0))
        ->group("");
    run_->add_flag("--json", arguments_.json,
                   "print the summary as one JSON object on stdout instead of the summary line");
    given_.push_back(
        run_->add_option("--debug-ray", arguments_.debug_ray,
                         "re-run ray RAY of shot SHOT alone and print its events, one a line; "
                         "writes no products")
            ->type_name("SHOT:RAY"));
  }

  void add_check() {
    check_ = app_.add_subcommand("check", "validate the configuration and its inputs, run nothing");
    check_->footer(
        "Examples:\n"
        "  glaswave check share/demo/demo.json\n"
        "  glaswave check pass.json --set track.shots=10000\n"
        "  glaswave check --schema > glaswave.schema.json\n"
        "On success: a first line `glaswave: CONFIG is valid: N shots, M off the terrain`, then "
        "what a run would do (track, sensor, terrain, vegetation, rays, estimated time and "
        "memory, products). Whatever `run` refuses before simulating, `check` refuses, with the "
        "same message.");
    add_config(check_, false);
    check_->add_flag("--schema", arguments_.schema,
                     "print the configuration's JSON Schema (draft 2020-12) and exit");
    // The manual's generated reference (scripts/docs-reference): the table of keys, the
    // product field table.
    check_->add_flag("--keys-markdown", arguments_.keys_markdown)->group("");
    check_->add_flag("--fields-json", arguments_.fields_json)->group("");
  }

  void add_sweep() {
    sweep_ = app_.add_subcommand(
        "sweep", "sensitivity study: the base case and each varied value, one key at a time");
    add_config(sweep_, true);
    sweep_->footer(
        "Example (the seed's Table 3):\n"
        "  glaswave sweep share/studies/base.json --vary canopy.pai=1,2,4,5 "
        "--vary canopy.lad=planophile,erectophile\n"
        "Writes sensitivity.csv and sensitivity.md (TR, CR, GR and their % change from the base "
        "case, per band). Manual: docs/guide/sweep.md.");
    sweep_
        ->add_option("--vary", variations_,
                     "a key and the values it takes, one key at a time, the others at the base "
                     "case; repeatable")
        ->type_name("KEY=V1,V2,...")
        ->required();
    given_.push_back(sweep_
                         ->add_option("--out", arguments_.out_dir,
                                      "output directory (default out/<config name>-sweep)")
                         ->type_name("DIR"));
    add_threads(sweep_);
    sweep_->add_flag("--quiet", arguments_.quiet, "no progress bar");
  }

  void add_brf() {
    brf_ = app_.add_subcommand(
        "brf", "scene reflectance under the sun (FLIGHT's mode): brf.json and scene.tif");
    brf_->footer(
        "Example:\n"
        "  glaswave brf forest.json --out out/forest-brf\n"
        "The sun, the views and the photons are the configuration's `brf` keys. Prints each "
        "band's albedo and BRF per view. Manual: docs/guide/brf.md.");
    add_config(brf_, true);
    given_.push_back(brf_->add_option("--out", arguments_.out_dir,
                                      "output directory (default out/<config name>-brf)")
                         ->type_name("DIR"));
    add_threads(brf_);
    brf_->add_flag("--quiet", arguments_.quiet, "no progress bar");
  }

  void add_voxelize() {
    voxelize_ = app_.add_subcommand(
        "voxelize",
        "an airborne lidar point cloud (LAS) -> a voxel grid of plant area density (NetCDF)");
    voxelize_->footer(
        "Example:\n"
        "  glaswave voxelize plot.las --out plot_voxels.nc --voxel-size-m 2\n"
        "The grid is then a configuration's vegetation. Manual: docs/vegetation.md.");
    voxelize_->add_option("CLOUD", arguments_.cloud_file, "point cloud (LAS 1.0-1.4)")
        ->type_name("CLOUD.las")
        ->required();
    given_.push_back(
        voxelize_->add_option("--out", arguments_.out_dir, "the grid to write (NetCDF)")
            ->type_name("GRID.nc")
            ->required());
    voxelize_
        ->add_option("--voxel-size-m", arguments_.voxel_size_m,
                     "voxel size, across and in height (m; default 1)")
        ->type_name("S");
    given_.push_back(voxelize_
                         ->add_option("--crs", arguments_.crs,
                                      "the cloud's CRS when the file has none (EPSG:32633, WKT)")
                         ->type_name("CRS"));
    voxelize_->add_flag("--force", arguments_.force, "replace an existing grid file at --out");
  }

  CLI::App& app_;
  Arguments& arguments_;
  std::vector<std::string> variations_;
  CLI::App* run_ = nullptr;
  CLI::App* check_ = nullptr;
  CLI::App* sweep_ = nullptr;
  CLI::App* brf_ = nullptr;
  CLI::App* voxelize_ = nullptr;
  std::unique_ptr<RetrievalCommands> retrieval_;  // table, retrieve
  std::vector<CLI::Option*> given_;               // options refused when given empty
  static constexpr std::uint64_t max_threads = 65536;
};

}  // namespace

int run_command_line(int argc, char** argv) {
  CLI::App app{
      "glaswave: Monte Carlo simulation of satellite waveform lidar over vegetation and terrain"};
  app.set_version_flag("--version", std::string("glaswave ") + GLASWAVE_VERSION);
  app.footer(
      "Examples:\n"
      "  glaswave check share/demo/demo.json     what a run would do, simulating nothing\n"
      "  glaswave run share/demo/demo.json       simulate it; products in out/demo\n"
      "  glaswave run --help                     a command's options\n"
      "Manual: docs/ in the source (./scripts/docs builds it; start at docs/index.md).");
  app.require_subcommand(1);
  Arguments arguments;
  Commands commands(app, arguments);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
    if (Cluster::world().rank() == 0)                // every process of mpirun has the same line
      std::fprintf(stderr, "glaswave: error: %s (see glaswave --help)\n",
                   escape_controls(e.what()).c_str());
    return 2;
  }
  // Under mpirun rank 0 alone reports an error every process met; one that this process met
  // alone ends them all.
  Cluster& cluster = Cluster::world();
  const auto report = [&](const char* what, int status) {
    if (cluster.rank() == 0 || !cluster.failed_together())
      std::fprintf(stderr, "glaswave: error: %s\n", what);
    if (cluster.rank() != 0 && !cluster.failed_together()) cluster.abort(status);
    return status;
  };
  try {
    return commands.dispatch(joined(argc, argv));
  } catch (const Error& e) {
    return report(escape_controls(e.what()).c_str(), e.exit_status());
  } catch (const std::bad_alloc&) {
    return report(
        "out of memory; the configuration's limits (the manual's docs/guide/limits.md) assume the "
        "machine's memory is free",
        static_cast<int>(ErrorKind::run));
  } catch (const std::exception& e) {
    return report(escape_controls(e.what()).c_str(), static_cast<int>(ErrorKind::run));
  }
}

}  // namespace glaswave
