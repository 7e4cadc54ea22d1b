// The benchmark that ./scripts/benchmark runs: whole runs (run_simulation, NetCDF and GeoJSON
// written, no plots) of the seed's base case, a bare 20 degree slope against flat ground, 19-ray
// shots (with and without the waveform metrics, with the footprints as GPKG, with NetCDF alone),
// one thread against every core, a raw Embree probe beside them, the share of each stage of a
// shot, and the per-shot floor in HELIOS++'s shape (19 rays, flat and 20 degrees, 4,000 and 40,000
// shots, one thread, NetCDF alone) against the rays' own cost, and a GEDI pass at 1000 rays over
// the demo's forest on rough ground (shots sharing strips) against its rays' own cost. Every
// figure is measured in this one run, so that the ratios hold on a shared machine whose absolute
// speed drifts. Not a test: `--quick` is the short mode that ctest runs.
#include <embree3/rtcore.h>
#include <sys/resource.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "footprints/track.hpp"
#include "pipeline/engine/inputs.hpp"
#include "pipeline/engine/run.hpp"
#include "pipeline/products/product_writer.hpp"
#include "pipeline/products/waveform_metrics.hpp"
#include "pipeline/shot/footprint_geometry.hpp"
#include "terrain/ground_mesh.hpp"

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// How much each case runs: the full benchmark, or the short mode that CI runs in seconds.
struct Sizes {
  int rounds;                    // every case run this many times, in turn; the fastest kept
  int base_shots, base_rays;     // the seed's base case (north2010, Table 1 forest, order 8)
  int slope_shots, slope_rays;   // bare ground, order 1, flat and 20 degrees
  int short_shots;               // 19 rays a shot over flat bare ground
  int stage_shots;               // shots timed stage by stage, one thread
  std::int64_t probe_rays;       // raw Embree queries
  int floor_shots[2];            // the per-shot floor's runs (HELIOS++'s 4,000 and 40,000 pulses)
  int ray_shots;                 // shots traced through one scene for the rays' own cost
  int gedi_shots[2], gedi_rays;  // the GEDI pass over the demo's forest and rough ground
};

constexpr Sizes full_sizes{3, 40,      10000,         400,  1000,    10000,
                           8, 4000000, {4000, 40000}, 4000, {8, 64}, 1000};
constexpr Sizes quick_sizes{1, 2, 500, 20, 200, 200, 2, 100000, {100, 1000}, 200, {8, 16}, 100};

// A pass northward over a plane facing east (45 N, 7 E, 172 m between shots), so that every shot
// meets the same ground, with the north2010 sensor.
glaswave::Config pass_config(int shots, int rays, int max_order, double slope_deg, bool forest) {
  nlohmann::json document = {
      {"seed", 1},
      {"sensor", {{"preset", "north2010"}}},
      {"simulation", {{"rays_per_shot", rays}, {"max_order", max_order}}},
      {"terrain",
       {{"plane",
         {{"origin_lat_deg", 45.0},
          {"origin_lon_deg", 7.0},
          {"slope_deg", slope_deg},
          {"aspect_deg", 90.0}}}}},
      {"canopy", forest ? nlohmann::json::object() : nlohmann::json()},  // {}: Table 1
      {"track",
       {{"type", "pass"},
        {"start_lat_deg", 45.0},
        {"start_lon_deg", 7.0},
        {"heading_deg", 0.0},
        {"shots", shots},
        {"spacing_m", 172.0}}},
  };
  return glaswave::parse_config(document);
}

// A GEDI pass (the gedi preset's coverage beam, shots 60 m apart) over the demo's forest
// (share/demo: PAI 3, cover 0.6, ellipsoid crowns) on a 15 degree plane with the demo's roughness
// (0.2 m RMS, 3 m correlation): shots that share strips, each meshing the relief under its beam.
glaswave::Config gedi_pass_config(int shots, int rays) {
  nlohmann::json document = {
      {"seed", 2005},
      {"sensor", {{"preset", "gedi"}}},
      {"simulation", {{"rays_per_shot", rays}, {"max_order", 8}}},
      {"terrain",
       {{"plane",
         {{"origin_lat_deg", 34.3},
          {"origin_lon_deg", -118.2},
          {"slope_deg", 15.0},
          {"aspect_deg", 60.0}}},
        {"roughness", {{"rms_m", 0.2}, {"correlation_m", 3.0}}},
        {"soil_reflectance", 0.25}}},
      {"canopy",
       {{"pai", 3.0},
        {"lad", "spherical"},
        {"cover", 0.6},
        {"crown_shape", "ellipsoid"},
        {"crown_radius_m", 6.0},
        {"crown_half_height_m", 7.0},
        {"crown_base_m", {8.0, 14.0}},
        {"leaf_reflectance", 0.45},
        {"leaf_transmittance", 0.45},
        {"bark_reflectance", 0.35}}},
      {"track",
       {{"type", "pass"},
        {"start_lat_deg", 34.3},
        {"start_lon_deg", -118.2},
        {"heading_deg", 10.0},
        {"shots", shots},
        {"spacing_m", 60.0}}},
  };
  return glaswave::parse_config(document);
}

fs::path scratch_path(const char* what) {
  static int count = 0;
  return fs::temp_directory_path() / ("glaswave-benchmark-" + std::to_string(getpid()) + "-" +
                                      what + "-" + std::to_string(count++));
}

// CPU time of the whole process so far (every thread, user and system), s.
double process_cpu_s() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  auto s = [](const timeval& t) { return t.tv_sec + 1e-6 * t.tv_usec; };
  return s(usage.ru_utime) + s(usage.ru_stime);
}

struct RunFigures {
  std::int64_t shots = 0, queries = 0;
  double seconds = 0.0;
  double cpu_seconds = 0.0;  // every thread's
  double shots_per_s() const { return shots / seconds; }
  double queries_per_s() const { return queries / seconds; }
};

// A whole run as `glaswave run` makes it (terrain, forest, track, shots, products), timed.
RunFigures whole_run(const glaswave::Config& config, int threads) {
  glaswave::RunRequest request;
  request.out_dir = scratch_path("run");
  request.threads = threads;
  const auto start = Clock::now();
  const double cpu_start_s = process_cpu_s();
  const glaswave::RunSummary summary = glaswave::run_simulation(config, request, {});
  RunFigures figures{summary.shots, summary.ray_queries, seconds_since(start),
                     process_cpu_s() - cpu_start_s};
  fs::remove_all(request.out_dir);
  return figures;
}

// Raw Embree: the ground mesh under the base case's first footprint, queried with rays from
// just above it, aimed downward across the footprint, on every core. The ceiling that the
// transport's own query rate is compared with.
double embree_probe_queries_per_s(const glaswave::Config& config, std::int64_t rays) {
  const auto terrain = glaswave::make_terrain(config.terrain);
  const glaswave::Track track(config.track, *terrain);
  const glaswave::LocalFrame frame(track.footprint(0).ground);
  const glaswave::GroundMesh mesh = glaswave::build_ground_mesh(*terrain, frame, 150.0, 5.0);
  RTCDevice device = rtcNewDevice(nullptr);
  RTCScene scene = rtcNewScene(device);
  RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  std::memcpy(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                      3 * sizeof(float), mesh.vertices_m.size() / 3),
              mesh.vertices_m.data(), mesh.vertices_m.size() * sizeof(float));
  std::memcpy(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                      3 * sizeof(unsigned), mesh.triangles.size() / 3),
              mesh.triangles.data(), mesh.triangles.size() * sizeof(unsigned));
  rtcCommitGeometry(geometry);
  rtcAttachGeometry(scene, geometry);
  rtcReleaseGeometry(geometry);
  rtcCommitScene(scene);
  const float top_m = static_cast<float>(mesh.max_height_m + 30.0);
  std::int64_t hits = 0;  // read, so that the queries are not optimised away
  const auto start = Clock::now();
  constexpr std::int64_t chunk = 4096;
  tbb::parallel_for(std::int64_t{0}, (rays + chunk - 1) / chunk, [&](std::int64_t c) {
    std::mt19937_64 engine(static_cast<std::uint64_t>(c));
    std::uniform_real_distribution<float> across(-30.0f, 30.0f), tilt(-0.05f, 0.05f);
    std::int64_t found = 0;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (std::int64_t i = 0; i < chunk; ++i) {
      RTCRayHit query{};
      query.ray.org_x = across(engine);
      query.ray.org_y = across(engine);
      query.ray.org_z = top_m;
      query.ray.dir_x = tilt(engine);
      query.ray.dir_y = tilt(engine);
      query.ray.dir_z = -1.0f;
      query.ray.tfar = 1.0e5f;
      query.ray.mask = ~0u;
      query.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(scene, &context, &query);
      found += query.hit.geomID != RTC_INVALID_GEOMETRY_ID;
    }
    __atomic_add_fetch(&hits, found, __ATOMIC_RELAXED);
  });
  const double seconds = seconds_since(start);
  rtcReleaseScene(scene);
  rtcReleaseDevice(device);
  const std::int64_t queries = (rays + chunk - 1) / chunk * chunk;
  return hits > 0 ? queries / seconds : 0.0;
}

// Seconds spent in each stage of `shots` shots on one thread: locating the footprints, the
// shot's scene and transport, its waveform processing (decomposition and metrics, timed again
// on a copy of the record), and writing the products.
struct StageSeconds {
  double footprints = 0.0, transport = 0.0, processing = 0.0, writing = 0.0;
  double total() const { return footprints + transport + processing + writing; }
};

StageSeconds stage_seconds(const glaswave::Config& config, int shots) {
  StageSeconds stages;
  const auto terrain = glaswave::make_terrain(config.terrain);
  const glaswave::Track track(config.track, *terrain);
  const std::unique_ptr<glaswave::ShotSimulator> made =
      glaswave::make_shot_simulator(config, *terrain);
  const glaswave::ShotSimulator& simulator = *made;
  auto start = Clock::now();
  const std::vector<glaswave::Footprint> footprints = track.footprints(0, shots);
  stages.footprints = seconds_since(start);
  glaswave::WaveformProcessing processing;
  processing.pulse_sigma_ns = config.sensor.pulse_sigma_ns;
  processing.noise_free = !config.detector.enabled;
  std::vector<glaswave::ShotRecord> records;
  double simulate_s = 0.0;
  for (const glaswave::Footprint& footprint : footprints) {
    start = Clock::now();
    records.push_back(simulator.simulate(footprint));
    simulate_s += seconds_since(start);
    glaswave::ShotRecord copy = records.back();
    start = Clock::now();
    glaswave::process_shot_waveforms(copy, config.sensor.bin_ns, processing);
    stages.processing += seconds_since(start);
  }
  stages.transport = simulate_s - stages.processing;
  const fs::path out = scratch_path("stages");
  fs::create_directories(out);
  start = Clock::now();
  {
    const auto writers =
        glaswave::make_writers(out, {}, glaswave::run_info(config, simulator, shots, "benchmark"));
    for (std::size_t i = 0; i < records.size(); ++i)
      for (const auto& writer : writers) writer->write(static_cast<std::int64_t>(i), records[i]);
    for (const auto& writer : writers) writer->finish({});
  }
  stages.writing = seconds_since(start);
  fs::remove_all(out);
  return stages;
}

// The rays' own cost of a shot, CPU s: its transport (the rays, their binning and the pulse)
// through a scene built once, under the track's first footprint, for `shots` shot numbers on one
// thread. What a shot would cost if the scene, the ground fit, the sun, the receiver and the
// record were free.
double rays_cpu_s_per_shot(const glaswave::Config& config, int shots) {
  const auto terrain = glaswave::make_terrain(config.terrain);
  const glaswave::Track track(config.track, *terrain);
  const auto simulator = glaswave::make_shot_simulator(config, *terrain);
  const glaswave::Footprint footprint = track.footprint(0);
  const glaswave::FootprintFrame where =
      glaswave::footprint_frame(*terrain, simulator->lidar(), footprint);
  const double half_size_m = glaswave::traced_patch_half_size_m(
      *terrain, simulator->lidar(), footprint, where.frame, simulator->lidar().max_angle_rad());
  const glaswave::BuiltScene built =
      simulator->scenes().build(where.frame, where.orientation, half_size_m, 0.0);
  const glaswave::TransportOptions options = glaswave::shot_settings(config).transport;
  double energy_J = 0.0;  // read, so that the shots are not optimised away
  tbb::task_arena one(1);
  const double cpu_start_s = process_cpu_s();
  one.execute([&] {
    for (int shot = 0; shot < shots; ++shot)
      energy_J += glaswave::simulate_shot(*built.scene, simulator->lidar(), where.geometry,
                                          built.optics, options, shot)
                      .energy_J[0];
  });
  const double cpu_s = process_cpu_s() - cpu_start_s;
  return energy_J > 0.0 ? cpu_s / shots : 0.0;
}

void print_run(const char* name, int rays, int threads, const RunFigures& f) {
  std::printf("%-34s %6lld %6d %7d %10.1f %12.3g %12.3g\n", name, static_cast<long long>(f.shots),
              rays, threads, f.shots_per_s(), static_cast<double>(f.queries) / f.shots,
              f.queries_per_s());
}

void print_stages(const char* name, const StageSeconds& s, int shots) {
  const double total = s.total();
  std::printf("%-22s %10.1f %12.1f %14.1f %9.1f %12.3g\n", name, 100.0 * s.footprints / total,
              100.0 * s.transport / total, 100.0 * s.processing / total, 100.0 * s.writing / total,
              total / shots);
}

// HELIOS++'s shape: 19 sub-rays a pulse, 4,000 and 40,000 pulses over a flat and a 20 degree
// plane on one thread, every product but the footprint polygons (NetCDF with the metrics).
// What a shot costs beyond its rays is the floor: CPU of the whole run a shot, and the marginal
// cost of a shot between the two runs (the run's fixed costs left out), each against the rays'
// own cost measured in the same rounds. Returns the figures, for the check that each came out.
std::vector<double> print_floor(const Sizes& n) {
  std::vector<double> floor_figures;
  std::printf(
      "per-shot floor, 19-ray shots, one thread, NetCDF alone (CPU, us a shot; the fastest of %d "
      "round%s):\n",
      n.rounds, n.rounds > 1 ? "s" : "");
  std::printf("%-12s %8s %10s %10s %12s %10s %10s\n", "plane", "shots", "run us", "rays us",
              "run / rays", "marginal", "/ rays");
  for (const double slope_deg : {0.0, 20.0}) {
    double run_cpu_s[2] = {0.0, 0.0}, rays_s = 0.0;
    for (int round = 0; round < n.rounds; ++round) {
      for (int k = 0; k < 2; ++k) {
        glaswave::Config floor_case = pass_config(n.floor_shots[k], 19, 8, slope_deg, false);
        floor_case.output.footprints = false;
        const double cpu_s = whole_run(floor_case, 1).cpu_seconds;
        if (round == 0 || cpu_s < run_cpu_s[k]) run_cpu_s[k] = cpu_s;
      }
      const double r = rays_cpu_s_per_shot(pass_config(1, 19, 8, slope_deg, false), n.ray_shots);
      if (round == 0 || r < rays_s) rays_s = r;
    }
    const double marginal_s = (run_cpu_s[1] - run_cpu_s[0]) / (n.floor_shots[1] - n.floor_shots[0]);
    for (int k = 0; k < 2; ++k) {
      const double per_shot_s = run_cpu_s[k] / n.floor_shots[k];
      std::printf("%-12s %8d %10.1f %10.1f %12.1f %10.1f %10.1f\n",
                  slope_deg == 0.0 ? "flat" : "20 degrees", n.floor_shots[k], 1e6 * per_shot_s,
                  1e6 * rays_s, per_shot_s / rays_s, 1e6 * marginal_s, marginal_s / rays_s);
      floor_figures.push_back(per_shot_s / rays_s);
    }
  }
  return floor_figures;  // the marginal costs left out: noise can make a short run's negative
}

// The GEDI pass on one thread, NetCDF and GeoJSON: CPU a shot of each run and the marginal CPU
// of a shot between the two runs (the run's start left out), against the rays' own cost (the
// transport through one shot's scene, built once). Returns the figures.
std::vector<double> print_gedi_pass(const Sizes& n) {
  std::printf(
      "GEDI pass, %d rays, the demo's forest on a rough 15 degree plane, shots 60 m apart, one "
      "thread (CPU, ms a shot; the fastest of %d round%s):\n",
      n.gedi_rays, n.rounds, n.rounds > 1 ? "s" : "");
  std::printf("%8s %10s %10s %12s %10s %10s\n", "shots", "run ms", "rays ms", "run / rays",
              "marginal", "/ rays");
  double run_cpu_s[2] = {0.0, 0.0}, rays_s = 0.0;
  for (int round = 0; round < n.rounds; ++round) {
    for (int k = 0; k < 2; ++k) {
      const double cpu_s = whole_run(gedi_pass_config(n.gedi_shots[k], n.gedi_rays), 1).cpu_seconds;
      if (round == 0 || cpu_s < run_cpu_s[k]) run_cpu_s[k] = cpu_s;
    }
    const double r = rays_cpu_s_per_shot(gedi_pass_config(1, n.gedi_rays), n.gedi_shots[0]);
    if (round == 0 || r < rays_s) rays_s = r;
  }
  const double marginal_s = (run_cpu_s[1] - run_cpu_s[0]) / (n.gedi_shots[1] - n.gedi_shots[0]);
  std::vector<double> figures;
  for (int k = 0; k < 2; ++k) {
    const double per_shot_s = run_cpu_s[k] / n.gedi_shots[k];
    std::printf("%8d %10.2f %10.2f %12.2f %10.2f %10.2f\n", n.gedi_shots[k], 1e3 * per_shot_s,
                1e3 * rays_s, per_shot_s / rays_s, 1e3 * marginal_s, marginal_s / rays_s);
    figures.push_back(per_shot_s / rays_s);
  }
  return figures;
}

}  // namespace

int main(int argc, char** argv) {
  // --floor: the per-shot floor's case alone; --gedi: the GEDI pass alone.
  bool quick = false, floor_only = false, gedi_only = false;
  for (int i = 1; i < argc; ++i) {
    quick = quick || std::strcmp(argv[i], "--quick") == 0;
    floor_only = floor_only || std::strcmp(argv[i], "--floor") == 0;
    gedi_only = gedi_only || std::strcmp(argv[i], "--gedi") == 0;
    if (std::strcmp(argv[i], "--quick") != 0 && std::strcmp(argv[i], "--floor") != 0 &&
        std::strcmp(argv[i], "--gedi") != 0) {
      std::fprintf(stderr, "usage: %s [--quick] [--floor] [--gedi]\n", argv[0]);
      return 2;
    }
  }
  const Sizes n = quick ? quick_sizes : full_sizes;
  auto measured = [](const std::vector<double>& figures) {
    for (double figure : figures)
      if (!(std::isfinite(figure) && figure > 0.0)) return false;
    return true;
  };
  if (floor_only || gedi_only) {
    bool all = true;
    if (floor_only) all = measured(print_floor(n)) && all;
    if (gedi_only) all = measured(print_gedi_pass(n)) && all;
    std::printf(all ? "every figure measured\n" : "a figure is missing\n");
    return all ? 0 : 1;
  }
  const int cores = tbb::this_task_arena::max_concurrency();
  const glaswave::Config base = pass_config(n.base_shots, n.base_rays, 8, 5.0, true);
  const glaswave::Config flat = pass_config(n.slope_shots, n.slope_rays, 1, 0.0, false);
  const glaswave::Config slope = pass_config(n.slope_shots, n.slope_rays, 1, 20.0, false);
  const glaswave::Config short_shots = pass_config(n.short_shots, 19, 8, 0.0, false);
  glaswave::Config short_no_metrics = short_shots;  // output.metrics false
  short_no_metrics.output.metrics = false;
  // Where the footprints go decides what a short shot costs: OGR's GeoJSON is most of it.
  glaswave::Config short_gpkg = short_shots;
  short_gpkg.output.footprints_format = "GPKG";
  glaswave::Config short_netcdf_only = short_shots;
  short_netcdf_only.output.footprints = false;

  std::printf(
      "glaswave benchmark%s: %d cores; whole runs (NetCDF and GeoJSON unless named, no plots), "
      "north2010 sensor, passes over planes; the fastest of %d round%s\n",
      quick ? " (--quick)" : "", cores, n.rounds, n.rounds > 1 ? "s" : "");
  std::printf("%-34s %6s %6s %7s %10s %12s %12s\n", "case", "shots", "rays", "threads", "shots/s",
              "queries/shot", "queries/s");
  // Cases side by side, each ratio's two halves run one after the other, in rounds: on a shared
  // machine the fastest of a case's runs is the one least slowed by others.
  const std::vector<std::pair<const glaswave::Config*, int>> cases = {
      {&base, cores},        {&base, 1},
      {&flat, cores},        {&slope, cores},
      {&short_shots, cores}, {&short_no_metrics, cores},
      {&short_gpkg, cores},  {&short_netcdf_only, cores}};
  std::vector<RunFigures> fastest(cases.size());
  double probe = 0.0;
  for (int round = 0; round < n.rounds; ++round) {
    for (std::size_t k = 0; k < cases.size(); ++k) {
      const RunFigures figures = whole_run(*cases[k].first, cases[k].second);
      if (round == 0 || figures.seconds < fastest[k].seconds) fastest[k] = figures;
      if (k == 0) probe = std::max(probe, embree_probe_queries_per_s(base, n.probe_rays));
    }
  }
  const RunFigures &base_all = fastest[0], &base_one = fastest[1], &flat_run = fastest[2],
                   &slope_run = fastest[3], &short_run = fastest[4], &short_bare_run = fastest[5],
                   &short_gpkg_run = fastest[6], &short_netcdf_run = fastest[7];
  print_run("base case (forest, order 8)", n.base_rays, cores, base_all);
  print_run("base case, one thread", n.base_rays, 1, base_one);
  print_run("bare flat ground (order 1)", n.slope_rays, cores, flat_run);
  print_run("bare 20 degree slope (order 1)", n.slope_rays, cores, slope_run);
  print_run("bare flat ground, 19-ray shots", 19, cores, short_run);
  print_run("19-ray shots, output.metrics false", 19, cores, short_bare_run);
  print_run("19-ray shots, footprints as GPKG", 19, cores, short_gpkg_run);
  print_run("19-ray shots, NetCDF only", 19, cores, short_netcdf_run);
  std::printf("%-34s %6s %6s %7d %10s %12s %12.3g\n", "raw Embree probe (ground mesh)", "", "",
              cores, "", "", probe);

  std::printf("ratios:\n");
  const double probe_ratio = base_all.queries_per_s() / probe;
  const double slope_ratio = slope_run.seconds / flat_run.seconds;
  const double scaling = base_all.shots_per_s() / base_one.shots_per_s();
  std::printf("  base case queries/s / raw Embree probe: %.3f\n", probe_ratio);
  std::printf("  20 degree slope / flat ground, time:     %.2f\n", slope_ratio);
  // CPU time is steadier on a shared machine: it leaves out time spent waiting for a core.
  std::printf("  20 degree slope / flat ground, CPU:      %.2f\n",
              slope_run.cpu_seconds / flat_run.cpu_seconds);
  std::printf("  thread scaling, base case (%d / 1):      %.2f\n", cores, scaling);

  std::printf("stage shares, one thread (%% of each case's time; %d and %d shots):\n",
              n.stage_shots, 100 * n.stage_shots);
  std::printf("%-22s %10s %12s %14s %9s %12s\n", "case", "footprints", "scene+transp",
              "decomp+metrics", "writing", "s/shot");
  const StageSeconds base_stages = stage_seconds(base, n.stage_shots);
  const StageSeconds short_stages = stage_seconds(short_shots, 100 * n.stage_shots);
  print_stages("base case", base_stages, n.stage_shots);
  print_stages("19-ray shots", short_stages, 100 * n.stage_shots);

  const std::vector<double> floor_figures = print_floor(n);
  const std::vector<double> gedi_figures = print_gedi_pass(n);

  // The short mode is a CI check that every figure came out.
  if (!measured(floor_figures) || !measured(gedi_figures)) {
    std::printf("a figure is missing\n");
    return 1;
  }
  for (double figure :
       {probe_ratio, slope_ratio, scaling, short_run.shots_per_s(), short_bare_run.shots_per_s(),
        short_gpkg_run.shots_per_s(), short_netcdf_run.shots_per_s(), base_stages.total(),
        short_stages.total()}) {
    if (!(std::isfinite(figure) && figure > 0.0)) {
      std::printf("a figure is missing\n");
      return 1;
    }
  }
  std::printf("every figure measured\n");
  return 0;
}
