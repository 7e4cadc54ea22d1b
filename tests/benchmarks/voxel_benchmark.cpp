// The voxel grids' benchmark that ./scripts/benchmark runs (issue 24), in one process:
//   - memory: a grid of 1 km x 1 km at 1 m with 50 layers of 1 m (200 MB of floats), written as
//     `voxelize` writes it (CF NetCDF, 64 x 64 columns a chunk, deflated), read by windows
//     during a whole run (run_simulation) of a 1000-shot GLAS pass across it on every core: the
//     process's peak resident memory, and the run's memory estimate (estimate_run_memory) beside
//     the resident memory the run added;
//   - speed: a shot over the seed's Table 1 forest of turbid crowns against the same crowns
//     voxelised at 1 m (their plant area kept), and a homogeneous layer against a grid of the
//     same uniform density, at the seed's settings (10 000 rays, order 8, Table 2's beam at nadir
//     from 600 km, one thread), the fastest of several rounds, with the energies of each pair;
//   - a point cloud of returns cast through the voxelised crowns: its voxelisation when the run
//     starts, and a shot over it.
// The grids are written by a child process (a 200 MB block would otherwise stay in this
// process's peak) into a temporary folder, deleted at the end. Not a test: `--quick` (a 300 m
// grid, 100 shots, 500 rays) is the short mode that ctest runs; `--speed` times the shots alone
// (no memory pass), `--rounds N` the fastest of N.
#include <sys/wait.h>
#include <tbb/task_arena.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <numbers>
#include <random>
#include <string>

#include "canopy/cloud_terrain.hpp"
#include "canopy/voxel_grid.hpp"
#include "pipeline/engine/machine.hpp"
#include "pipeline/engine/run.hpp"
#include "pipeline/shot/forest_source.hpp"
#include "pipeline/shot/voxel_source.hpp"
#include "tests/benchmarks/process_memory.hpp"
#include "tests/canopy/las_fixture.hpp"
#include "tests/pipeline/shot/shot_test_support.hpp"

namespace {

namespace fs = std::filesystem;
using namespace glaswave;
using Clock = std::chrono::steady_clock;
using benchmarks::status_mib;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// Runs `write` in a child process, so that what it allocates stays out of this one's peak.
bool in_child(const std::function<void()>& write) {
  std::fflush(stdout);
  const pid_t child = fork();
  if (child == 0) {
    try {
      write();
    } catch (const std::exception& e) {
      std::fprintf(stderr, "voxel_benchmark: %s\n", e.what());
      _exit(1);
    }
    _exit(0);
  }
  int status = 0;
  return child > 0 && waitpid(child, &status, 0) == child && WIFEXITED(status) &&
         WEXITSTATUS(status) == 0;
}

// The memory grid: `side` x `side` columns of 1 m in UTM 32N about 45 N 7 E, 50 layers of 1 m,
// a canopy of varying height (15 to 35 m) and density, so that it compresses as a forest does.
VoxelBlock forest_grid(int side) {
  VoxelBlock b;
  b.crs_wkt = "EPSG:32632";
  b.nx = b.ny = side;
  b.nz = 50;
  b.x0 = 342369.0 - side / 2.0;
  b.y0 = 4984896.0 - side / 2.0;
  for (int k = 0; k <= b.nz; ++k) b.z_edges_m.push_back(k);
  b.pad.assign(std::size_t(side) * side * b.nz, 0.0f);
  std::mt19937 bits(5);
  std::uniform_real_distribution<float> noise(0.5f, 1.5f);
  for (int j = 0; j < side; ++j)
    for (int i = 0; i < side; ++i) {
      const double top_m = 25.0 + 7.0 * std::sin(i / 23.0) * std::cos(j / 17.0) + 3.0 * noise(bits);
      for (int k = static_cast<int>(0.5 * top_m); k < top_m && k < b.nz; ++k)
        b.pad[(std::size_t(k) * side + j) * side + i] = 0.3f * noise(bits);
    }
  return b;
}

// A GLAS pass of `shots` shots 1 m apart, north along 7 E across the grid, over a level plane.
Config pass_config(const fs::path& grid, int shots, int rays) {
  const double south_deg = 45.0 - 0.5 * shots / 111132.0;
  nlohmann::json document = {
      {"seed", 24},
      {"sensor", {{"preset", "glas"}}},
      {"simulation", {{"rays_per_shot", rays}, {"max_order", 3}}},
      {"terrain",
       {{"plane", {{"origin_lat_deg", 45.0}, {"origin_lon_deg", 7.0}, {"elevation_m", 0.0}}},
        {"soil_reflectance", 0.25}}},
      {"canopy", {{"voxels", {{"file", grid.string()}}}}},
      {"track",
       {{"type", "pass"},
        {"start_lat_deg", south_deg},
        {"start_lon_deg", 7.0},
        {"heading_deg", 0.0},
        {"shots", shots},
        {"spacing_m", 1.0},
        {"altitude_m", 600000.0}}},
      {"output", {{"netcdf", true}, {"footprints", false}, {"plots", false}}},
  };
  return parse_config(document);
}

// Resets the process's peak resident memory (VmHWM) to what it holds now.
void reset_peak() { std::ofstream("/proc/self/clear_refs") << "5"; }

struct PassMemory {
  double seconds = 0, added_mib = 0, bare_added_mib = 0, estimate_mib = 0, region_mib = 0;
  double source_mib = 0;
  int threads = 0;
  std::int64_t shots = 0;
};

// A whole run: the resident memory it added at its peak above what the process held before.
double run_added_mib(const Config& config, const fs::path& out, std::int64_t* shots = nullptr) {
  RunRequest request;
  request.out_dir = out;
  reset_peak();
  const double before_mib = status_mib("VmRSS");
  const std::int64_t done = run_simulation(config, request, {}).shots;
  if (shots) *shots = done;
  fs::remove_all(out);
  return status_mib("VmHWM") - before_mib;
}

PassMemory memory_pass(const fs::path& folder, int side, int shots, int rays) {
  const fs::path grid = folder / "forest_pad.nc";
  PassMemory m;
  if (!in_child([&] { write_voxel_netcdf(grid, forest_grid(side)); })) return m;
  std::printf("  grid: %d x %d columns x 50 layers of 1 m, %.1f MiB of floats, %.1f MiB on disk\n",
              side, side, side * side * 50 * 4 / 1048576.0, fs::file_size(grid) / 1048576.0);
  const Config config = pass_config(grid, shots, rays);
  const RunMemory estimate = estimate_run_memory(config);
  m.estimate_mib = estimate.bytes / 1048576.0;
  m.region_mib = estimate.scene_bytes / 1048576.0;
  m.source_mib = estimate.source_bytes / 1048576.0;
  m.threads = estimate.threads;
  // The same pass over bare ground first: what the run holds without vegetation.
  Config bare = config;
  bare.canopy.reset();
  m.bare_added_mib = run_added_mib(bare, folder / "bare");
  const auto start = Clock::now();
  m.added_mib = run_added_mib(config, folder / "pass", &m.shots);
  m.seconds = seconds_since(start);
  return m;
}

// Local east/north about the footprint as a transverse Mercator centred on it: within the
// scene's few hundred metres it is the shot's frame to well under a millimetre.
constexpr const char* footprint_tmerc =
    "+proj=tmerc +lat_0=45 +lon_0=7 +k=1 +x_0=0 +y_0=0 +datum=WGS84 +units=m +type=crs";

// The crowns of `region` as a grid of 1 m voxels (x, y east and north of the footprint) over
// [-half_m, half_m]^2, each voxel holding the crowns' density times the part of it inside them
// (sub^3 points a voxel), with layers up to the highest crown; heights above the ground.
VoxelBlock voxelise_crowns(const RegionVegetation& forest, const Terrain& terrain,
                           const LocalFrame& frame, double half_m, int sub) {
  VoxelBlock b;
  b.crs_wkt = footprint_tmerc;
  b.nx = b.ny = static_cast<int>(2 * half_m);
  b.x0 = b.y0 = -half_m;
  double top_m = 0.0;
  for (const Crown& crown : forest.geometry.crowns)
    top_m = std::max(top_m, crown.base_m[2] + 2 * crown.half_height_m);
  b.nz = static_cast<int>(std::ceil(top_m + 1.0));
  for (int k = 0; k <= b.nz; ++k) b.z_edges_m.push_back(k);
  b.pad.assign(std::size_t(b.nx) * b.ny * b.nz, 0.0f);
  const auto ground_m = [&](double x, double y) {
    const Geodetic g = frame.to_geodetic({x, y, 0.0});
    return frame.to_local(
        Geodetic{g.lat_deg, g.lon_deg, terrain.height_m(g.lat_deg, g.lon_deg)})[2];
  };
  for (const Crown& c : forest.geometry.crowns) {
    const double ground = ground_m(c.base_m[0], c.base_m[1]);
    const double centre_z = c.base_m[2] - ground + c.half_height_m;
    const int i0 = std::max(0, static_cast<int>(std::floor(c.base_m[0] - c.radius_m - b.x0)));
    const int i1 = std::min(b.nx, static_cast<int>(std::ceil(c.base_m[0] + c.radius_m - b.x0)));
    const int j0 = std::max(0, static_cast<int>(std::floor(c.base_m[1] - c.radius_m - b.y0)));
    const int j1 = std::min(b.ny, static_cast<int>(std::ceil(c.base_m[1] + c.radius_m - b.y0)));
    const int k0 = std::max(0, static_cast<int>(std::floor(centre_z - c.half_height_m)));
    const int k1 = std::min(b.nz, static_cast<int>(std::ceil(centre_z + c.half_height_m)));
    for (int k = k0; k < k1; ++k)
      for (int j = j0; j < j1; ++j)
        for (int i = i0; i < i1; ++i) {
          int inside = 0;
          for (int s = 0; s < sub * sub * sub; ++s) {
            const double x = b.x0 + i + (s % sub + 0.5) / sub - c.base_m[0];
            const double y = b.y0 + j + (s / sub % sub + 0.5) / sub - c.base_m[1];
            const double z = k + (s / sub / sub + 0.5) / sub - centre_z;
            const double r = (x * x + y * y) / (c.radius_m * c.radius_m) +
                             z * z / (c.half_height_m * c.half_height_m);
            inside += r <= 1.0;
          }
          b.pad[(std::size_t(k) * b.ny + j) * b.nx + i] +=
              static_cast<float>(c.area_density_m2_m3 * inside / (sub * sub * sub));
        }
  }
  return b;
}

double plant_area_m2(const VoxelBlock& b) {
  double sum = 0.0;
  for (int j = 0; j < b.ny; ++j)
    for (int i = 0; i < b.nx; ++i) sum += b.plant_area_index(i, j) * b.dx * b.dy;
  return sum;
}

// A uniform grid of `pad` between `bottom_m` and `top_m` in 1 m layers, 1 m columns.
VoxelBlock uniform_slab(double half_m, double bottom_m, double top_m, double pad) {
  VoxelBlock b;
  b.crs_wkt = footprint_tmerc;
  b.nx = b.ny = static_cast<int>(2 * half_m);
  b.x0 = b.y0 = -half_m;
  b.z_edges_m.push_back(bottom_m);
  for (double z = bottom_m + 1.0; z < top_m + 1e-9; z += 1.0) b.z_edges_m.push_back(z);
  b.nz = static_cast<int>(b.z_edges_m.size()) - 1;
  b.pad.assign(std::size_t(b.nx) * b.ny * b.nz, static_cast<float>(pad));
  return b;
}

// An ALS-like cloud of a grid: vertical pulses, 4 a square metre at random, each returning once,
// where Beer-Lambert (G = 1/2) stops it in the voxels, or on the ground (class 2).
void cast_cloud(const VoxelBlock& grid, const fs::path& file) {
  test::LasFixture las;
  las.version_minor = 4;
  las.point_format = 6;
  las.offset[0] = las.offset[1] = las.offset[2] = 0.0;
  std::mt19937_64 bits(9);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const int pulses = 4 * grid.nx * grid.ny;
  las.points.reserve(pulses);
  for (int p = 0; p < pulses; ++p) {
    const double x = grid.x0 + grid.nx * unit(bits), y = grid.y0 + grid.ny * unit(bits);
    int i = 0, j = 0;
    grid.column_of(x, y, i, j);
    double depth = -std::log(1.0 - unit(bits)) / 0.5, z = 0.0;
    for (int k = grid.nz - 1; k >= 0 && z == 0.0; --k) {
      const double dz = grid.z_edges_m[k + 1] - grid.z_edges_m[k], tau = grid.at(i, j, k) * dz;
      if (depth < tau) z = grid.z_edges_m[k + 1] - depth / grid.at(i, j, k);
      depth -= tau;
    }
    test::LasFixturePoint point;
    point.x = x;
    point.y = y;
    point.z = z;
    point.classification = z > 0.0 ? 5 : 2;
    las.points.push_back(point);
  }
  test::write_las(file, las);
}

struct Timed {
  double seconds = 1e300, fixed_seconds = 1e300;
  double cpu_s = 1e300, fixed_cpu_s = 1e300;  // the shot's thread's CPU time
  ShotRecord record;
};

// The calling thread's CPU time: the shot runs on it (an arena of one thread), and it leaves out
// what the shared machine's other processes take.
double thread_cpu_s() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return now.tv_sec + 1e-9 * now.tv_nsec;
}

// The fastest of `rounds` shots over `vegetation`, and of as many at one ray (the shot's fixed
// cost: its scene, its truth).
void time_shots(
    const ShotSettings& shot, const Terrain& terrain, const Footprint& footprint,
    std::vector<std::pair<Timed*, std::function<std::unique_ptr<VegetationSource>()>>> sources,
    int rounds) {
  ShotSettings one_ray = shot;
  one_ray.transport.rays = 1;
  std::vector<std::unique_ptr<ShotSimulator>> full, fixed;
  for (auto& [timed, make] : sources) {
    full.push_back(std::make_unique<ShotSimulator>(
        shot, terrain, make(), make_receiver(testing::receiver_settings(shot, "waveform"))));
    fixed.push_back(std::make_unique<ShotSimulator>(
        one_ray, terrain, make(), make_receiver(testing::receiver_settings(one_ray, "waveform"))));
  }
  tbb::task_arena one_thread(1);
  one_thread.execute([&] {
    for (int round = 0; round < rounds; ++round)
      for (std::size_t s = 0; s < sources.size(); ++s) {
        Timed& t = *sources[s].first;
        auto start = Clock::now();
        double cpu_start_s = thread_cpu_s();
        t.record = full[s]->simulate(footprint);
        t.cpu_s = std::min(t.cpu_s, thread_cpu_s() - cpu_start_s);
        t.seconds = std::min(t.seconds, seconds_since(start));
        start = Clock::now();
        cpu_start_s = thread_cpu_s();
        fixed[s]->simulate(footprint);
        t.fixed_cpu_s = std::min(t.fixed_cpu_s, thread_cpu_s() - cpu_start_s);
        t.fixed_seconds = std::min(t.fixed_seconds, seconds_since(start));
      }
  });
}

void print_row(const char* name, const Timed& t) {
  std::printf("  %-22s %9.3f %13.3f %8.3f %8.3f %9.3f %11.3f %12.5g %12.5g\n", name, t.seconds,
              t.fixed_seconds, t.cpu_s, t.fixed_cpu_s, t.record.pai_true, t.record.cover_true,
              t.record.rx_energy_J[0], t.record.rx_energy_ground_J[0]);
}

}  // namespace

int main(int argc, char** argv) {
  // --speed: the shots' speed alone (no memory pass), as profiling wants; --rounds N.
  bool quick = false, speed_only = false;
  int rounds_asked = 0;
  for (int a = 1; a < argc; ++a) {
    if (std::strcmp(argv[a], "--quick") == 0) quick = true;
    if (std::strcmp(argv[a], "--speed") == 0) speed_only = true;
    if (std::strcmp(argv[a], "--rounds") == 0 && a + 1 < argc) rounds_asked = std::atoi(argv[++a]);
  }
  const int side = quick ? 200 : 1000, pass_shots = quick ? 30 : 1000;
  const int rays = quick ? 500 : 10000;
  const int rounds = rounds_asked > 0 ? rounds_asked : quick ? 1 : 5;
  const fs::path folder =
      fs::temp_directory_path() / ("glaswave-voxel-benchmark-" + std::to_string(getpid()));
  fs::create_directories(folder);

  std::printf("voxel grids%s\nmemory: a %d-shot GLAS pass, 100 rays, order 3, every core\n",
              quick ? " (--quick)" : "", pass_shots);
  const PassMemory pass = speed_only ? PassMemory{} : memory_pass(folder, side, pass_shots, 100);
  const double peak_mib = status_mib("VmHWM");
  if (!speed_only) {
    std::printf(
        "  %lld shots in %.1f s; the run's peak added %.1f MiB of resident memory to the "
        "process, over bare ground %.1f MiB (process peak %.1f MiB)\n",
        static_cast<long long>(pass.shots), pass.seconds, pass.added_mib, pass.bare_added_mib,
        peak_mib);
    std::printf(
        "  the estimate (estimate_run_memory): %.1f MiB in all; the voxels' %.1f MiB once "
        "+ %d threads x %.1f MiB, against %.1f MiB measured above bare ground\n",
        pass.estimate_mib, pass.source_mib, pass.threads, pass.region_mib,
        pass.added_mib - pass.bare_added_mib);
  }

  // The speed: Table 1's forest about Table 2's footprint, and its crowns as voxels.
  const std::unique_ptr<Terrain> terrain = testing::plane_terrain(0.3);
  const Footprint footprint = testing::nadir_footprint(*terrain);
  const LocalFrame frame(footprint.ground);
  VegetationSettings forest;
  forest.canopy.leaf_reflectance = {0.45};
  forest.canopy.leaf_transmittance = {0.45};
  forest.canopy.bark_reflectance = {0.3};
  const double half_m = quick ? 80.0 : 260.0;  // beyond the scene's 246 m
  const RegionVegetation crowns = ForestSource(forest).grow({*terrain, frame, half_m, {}, 1});
  // Every crown inside the grid (their radius is 8 m).
  const VoxelBlock voxelised =
      voxelise_crowns(crowns, *terrain, frame, half_m + 10.0, quick ? 4 : 8);
  VegetationSettings voxels = forest;
  voxels.canopy.kind = "voxels";
  voxels.canopy.voxels_file = (folder / "crowns_pad.nc").string();
  VegetationSettings layer = forest;
  layer.canopy.crown_shape = CrownShape::layer;
  layer.canopy.bark_fraction = 0.0;
  layer.canopy.green_fraction = 1.0;
  VegetationSettings slab = layer;
  slab.canopy.kind = "voxels";
  slab.canopy.voxels_file = (folder / "slab_pad.nc").string();
  // The layer's heights, as ForestSource grows it.
  const double layer_bottom_m = forest.canopy.crown_base_m[0];
  const double layer_top_m = layer_bottom_m + 2 * forest.canopy.crown_half_height_m;
  const bool written = in_child([&] {
    write_voxel_netcdf(voxels.canopy.voxels_file, voxelised);
    write_voxel_netcdf(slab.canopy.voxels_file,
                       uniform_slab(half_m, layer_bottom_m, layer_top_m,
                                    forest.canopy.pai / (layer_top_m - layer_bottom_m)));
  });
  double crowns_area_m2 = 0.0;
  for (const Crown& c : crowns.geometry.crowns)
    crowns_area_m2 += c.area_density_m2_m3 * 4.0 / 3.0 * std::numbers::pi * c.radius_m *
                      c.radius_m * c.half_height_m;

  // A point cloud cast through the voxelised crowns, voxelised again when its source is made.
  VegetationSettings cloud = voxels;
  cloud.canopy.kind = "point_cloud";
  cloud.canopy.point_cloud_file = (folder / "crowns.las").string();
  cloud.canopy.point_cloud_crs = footprint_tmerc;
  cloud.canopy.voxel_size_m = 1.0;
  cast_cloud(voxelised, cloud.canopy.point_cloud_file);
  auto start = Clock::now();
  const VoxelSource voxelised_cloud(cloud);
  const double voxelise_s = seconds_since(start);
  // The cloud as its own ground too (terrain.point_cloud): the terrain grids its class-2 points
  // and the voxelisation takes that grid, against the voxelisation gridding them again (as it
  // did until issue 24's fix); the fastest of the rounds, each source the same bits.
  TerrainSettings cloud_ground;
  cloud_ground.point_cloud = true;
  double shared_s = 1e300, twice_s = 1e300;
  bool same_grid = true;
  for (int round = 0; round < rounds; ++round) {
    start = Clock::now();
    const std::unique_ptr<Terrain> shared_terrain = point_cloud_terrain(cloud_ground, cloud.canopy);
    VegetationSettings shared = cloud;
    shared.cloud_ground = cloud_ground_of(*shared_terrain);
    const VoxelSource shared_source(shared);
    shared_s = std::min(shared_s, seconds_since(start));
    start = Clock::now();
    const std::unique_ptr<Terrain> own_terrain = point_cloud_terrain(cloud_ground, cloud.canopy);
    const VoxelSource own_source(cloud);
    twice_s = std::min(twice_s, seconds_since(start));
    same_grid = same_grid && shared_source.grid().shape().pad == own_source.grid().shape().pad;
  }

  ShotSettings shot = testing::shot_settings(0.3, rays);
  shot.transport.max_order = 8;
  Timed over_crowns, over_voxels, over_layer, over_slab, over_cloud;
  const auto source = [](const VegetationSettings& s) {
    return [s] { return make_vegetation_source(s); };
  };
  if (written)
    time_shots(shot, *terrain, footprint,
               {{&over_crowns, source(forest)},
                {&over_voxels, source(voxels)},
                {&over_layer, source(layer)},
                {&over_slab, source(slab)},
                {&over_cloud, source(cloud)}},
               rounds);
  fs::remove_all(folder);

  std::printf("speed: Table 2's shot at nadir, %d rays, order 8, one thread, fastest of %d\n", rays,
              rounds);
  std::printf(
      "  Table 1's crowns about the footprint (%zu in %.0f m x %.0f m): %.0f m2 of plant; "
      "voxelised at 1 m: %.0f m2 (%+.2f %%)\n",
      crowns.geometry.crowns.size(), 2 * half_m + 20, 2 * half_m + 20, crowns_area_m2,
      plant_area_m2(voxelised), 100.0 * (plant_area_m2(voxelised) / crowns_area_m2 - 1.0));
  std::printf("  point cloud: %zu returns, 4 pulses/m2, voxelised at start in %.2f s\n",
              std::size_t(4) * voxelised.nx * voxelised.ny, voxelise_s);
  std::printf(
      "  the cloud as its own terrain too: terrain and voxels in %.2f s, the ground gridded once "
      "(%.2f s gridded twice: %.2f times as long); the grids %s\n",
      shared_s, twice_s, twice_s / shared_s, same_grid ? "the same bits" : "DIFFER");
  std::printf("  %-22s %9s %13s %8s %8s %9s %11s %12s %12s\n", "shot over", "seconds",
              "at 1 ray (s)", "cpu (s)", "cpu 1 ray", "pai_true", "cover_true", "rx_energy_J",
              "ground_J");
  print_row("turbid crowns", over_crowns);
  print_row("crowns as voxels", over_voxels);
  print_row("point cloud of them", over_cloud);
  print_row("turbid layer", over_layer);
  print_row("layer as voxels", over_slab);
  std::printf("ratios:\n");
  std::printf("  voxels / turbid crowns, time:             %.2f (the rays alone: %.2f)\n",
              over_voxels.seconds / over_crowns.seconds,
              (over_voxels.seconds - over_voxels.fixed_seconds) /
                  (over_crowns.seconds - over_crowns.fixed_seconds));
  std::printf("  point cloud / turbid crowns, time:        %.2f\n",
              over_cloud.seconds / over_crowns.seconds);
  std::printf("  voxel slab / turbid layer, time:          %.2f\n",
              over_slab.seconds / over_layer.seconds);
  std::printf(
      "  the same by the shot's thread's CPU time: voxels / crowns %.2f (the rays alone: "
      "%.2f), point cloud / crowns %.2f, slab / layer %.2f\n",
      over_voxels.cpu_s / over_crowns.cpu_s,
      (over_voxels.cpu_s - over_voxels.fixed_cpu_s) / (over_crowns.cpu_s - over_crowns.fixed_cpu_s),
      over_cloud.cpu_s / over_crowns.cpu_s, over_slab.cpu_s / over_layer.cpu_s);
  std::printf("  voxels / crowns, energy:                  %.4f\n",
              over_voxels.record.rx_energy_J[0] / over_crowns.record.rx_energy_J[0]);
  std::printf("  voxel slab / layer, energy:               %.4f\n",
              over_slab.record.rx_energy_J[0] / over_layer.record.rx_energy_J[0]);
  if (!speed_only) {
    std::printf("  pass's peak resident memory / 1 GiB:      %.3f\n", peak_mib / 1024.0);
    std::printf("  voxels' memory, estimate / measured:      %.2f\n",
                (pass.source_mib + pass.threads * pass.region_mib) /
                    (pass.added_mib - pass.bare_added_mib));
  }
  // Every digit, so that a change of the traversal can be seen to keep the bits.
  std::printf("energies (J): voxels %.17g, point cloud %.17g, slab %.17g\n",
              over_voxels.record.rx_energy_J[0], over_cloud.record.rx_energy_J[0],
              over_slab.record.rx_energy_J[0]);
  const bool measured = (speed_only || (pass.shots == pass_shots && pass.added_mib > 0)) &&
                        written && over_voxels.seconds < 1e300 && over_crowns.seconds < 1e300 &&
                        over_cloud.seconds < 1e300 && same_grid;
  std::printf(measured ? "every figure measured\n" : "a figure is missing\n");
  return measured ? 0 : 1;
}
