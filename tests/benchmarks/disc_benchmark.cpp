// Disc leaves against triangles (issue 41), run by ./scripts/benchmark: the same leaves as
// oriented discs and as 12-gons of equal area (12 triangles each), in HET01-like floating spheres
// (uniform centres, spherical normals, LAI 5 over a sphere's cross-section, 11-19 m up) instanced
// over 1 ha at HET01's cover (0.471), one shot of RAMI-IV's lidar (a uniform 50 m footprint at
// nadir from 600 km, order 8, NIR optics, one thread).
// The shot's CPU time as a ratio measured in this one process (the fastest of a few rounds, each
// round both kinds in turn), so that it holds on a shared machine; each kind's peak resident
// memory in a child process of its own (read, built, one shot), so that neither inherits the
// other's pages. Not a test: `--quick` is the short mode that ctest runs.
#include <sys/wait.h>
#include <tbb/task_arena.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <string>

#include "pipeline/shot/facet_source.hpp"
#include "tests/benchmarks/process_memory.hpp"
#include "tests/pipeline/shot/shot_test_support.hpp"

namespace {

namespace fs = std::filesystem;
using namespace glaswave;
using Clock = std::chrono::steady_clock;
using benchmarks::status_mib;

constexpr double disc_radius_m = 0.1;  // HET01's
constexpr int gon_sides = 12;

// One sphere's leaves: centres uniform in the sphere, normals uniform on the unit sphere; as
// discs (RAMI's .def lines) and as regular 12-gons of the disc's area, 3 rho^2 = pi r^2.
void write_models(const fs::path& folder, double sphere_m, int leaves) {
  std::ofstream def(folder / "sphere.def");
  def << "# radius x y z nx ny nz\n";
  std::ofstream obj(folder / "sphere.obj");
  std::ofstream(folder / "sphere.mtl") << "newmtl leaf\n";
  obj << "mtllib sphere.mtl\nusemtl leaf\n";
  std::mt19937_64 bits(41);
  auto uniform = [&bits] { return static_cast<double>(bits() >> 11) * 0x1.0p-53; };
  const double rho = disc_radius_m * std::sqrt(std::numbers::pi / 3.0);
  for (int k = 0; k < leaves; ++k) {
    Vec3 c;
    do c = {2 * uniform() - 1, 2 * uniform() - 1, 2 * uniform() - 1};
    while (dot(c, c) > 1.0);
    c = sphere_m * c;
    const double cos_t = 2 * uniform() - 1, phi = 2 * std::numbers::pi * uniform();
    const double sin_t = std::sqrt(1 - cos_t * cos_t);
    const Vec3 n{sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t};
    def << disc_radius_m << ' ' << c[0] << ' ' << c[1] << ' ' << c[2] << ' ' << n[0] << ' ' << n[1]
        << ' ' << n[2] << '\n';
    const Vec3 helper = std::abs(n[2]) < 0.9 ? Vec3{0, 0, 1} : Vec3{1, 0, 0};
    const Vec3 u = normalized(cross(n, helper)), v = cross(n, u);
    obj << "v " << c[0] << ' ' << c[1] << ' ' << c[2] << '\n';
    for (int corner = 0; corner < gon_sides; ++corner) {
      const double a = 2 * std::numbers::pi * corner / gon_sides;
      const Vec3 p = c + rho * (std::cos(a) * u + std::sin(a) * v);
      obj << "v " << p[0] << ' ' << p[1] << ' ' << p[2] << '\n';
    }
    const int centre = (gon_sides + 1) * k + 1;
    for (int corner = 0; corner < gon_sides; ++corner)
      obj << "f " << centre << ' ' << centre + 1 + corner << ' '
          << centre + 1 + (corner + 1) % gon_sides << '\n';
  }
}

// Spheres on a jittered grid over 100 m x 100 m, floating (z_m) 11 to 19 m up as HET01's.
void write_trees(const fs::path& folder, int spheres) {
  std::ofstream csv(folder / "trees.csv");
  csv << "x,y,model,rotation_deg,scale,z_m\n";
  std::mt19937_64 bits(11);
  auto uniform = [&bits] { return static_cast<double>(bits() >> 11) * 0x1.0p-53; };
  const int side = static_cast<int>(std::ceil(std::sqrt(spheres)));
  const double step_m = 100.0 / side;
  for (int k = 0; k < spheres; ++k)
    csv << -50.0 + step_m * (k % side + uniform()) << ',' << -50.0 + step_m * (k / side + uniform())
        << ",sphere,0,1," << 11.0 + 8.0 * uniform() << '\n';
}

VegetationSettings settings_for(const fs::path& folder, const char* model) {
  VegetationSettings settings;
  settings.plane = PlaneSettings{testing::kLat0, testing::kLon0, 0.0, 0.0, 0.0};
  settings.canopy.kind = "facets";
  settings.canopy.facet_trees_file = (folder / "trees.csv").string();
  settings.canopy.facet_models = {{"sphere", (folder / model).string()}};
  settings.canopy.facet_materials = {{"leaf", {0.4957}, {0.4409}, true}};
  return settings;
}

double thread_cpu_s() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

struct Case {
  std::unique_ptr<ShotSimulator> simulator;
  double cpu_s = 1e300, wall_s = 1e300;
  ShotRecord record;
};

std::unique_ptr<ShotSimulator> simulator_for(const VegetationSettings& settings,
                                             const Terrain& terrain, int rays) {
  ShotSettings shot = testing::shot_settings(0.159, rays);
  shot.transport.max_order = 8;
  shot.lidar.beam_profile = "uniform";
  shot.lidar.divergence_sigma_rad = 25.0 / (2.0 * 600000.0);  // a 50 m disc
  return std::make_unique<ShotSimulator>(
      shot, terrain, std::make_unique<FacetSource>(settings),
      make_receiver(testing::receiver_settings(shot, "waveform")));
}

// A child process reads the model, builds a shot's scene and traces it; it reports its peak
// resident memory above what it started with (MiB), and the wall time to its first shot's end.
bool child_memory(const VegetationSettings& settings, double& peak_mib, double& load_s) {
  int ends[2];
  if (pipe(ends) != 0) return false;
  const pid_t pid = fork();
  if (pid < 0) return false;
  if (pid == 0) {
    close(ends[0]);
    const double start_mib = status_mib("VmRSS");
    const auto start = Clock::now();
    const std::unique_ptr<Terrain> terrain = testing::plane_terrain(0.159);
    double out[2] = {0.0, 0.0};
    {
      tbb::task_arena one_thread(1);
      one_thread.execute([&] {
        const auto simulator = simulator_for(settings, *terrain, 1);
        simulator->simulate(testing::nadir_footprint(*terrain));
      });
    }
    out[0] = status_mib("VmHWM") - start_mib;
    out[1] = std::chrono::duration<double>(Clock::now() - start).count();
    const bool sent = write(ends[1], out, sizeof out) == static_cast<ssize_t>(sizeof out);
    _exit(sent ? 0 : 1);
  }
  close(ends[1]);
  double in[2] = {0.0, 0.0};
  const bool got = read(ends[0], in, sizeof in) == static_cast<ssize_t>(sizeof in);
  close(ends[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  peak_mib = in[0];
  load_s = in[1];
  return got && WIFEXITED(status) && WEXITSTATUS(status) == 0;
}

}  // namespace

int main(int argc, char** argv) {
  const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
  // LAI 5 over a sphere's cross-section: N pi r^2 = 5 pi R^2.
  const double sphere_m = quick ? 2.0 : 4.0;
  const int leaves =
      static_cast<int>(std::lround(5.0 * sphere_m * sphere_m / (disc_radius_m * disc_radius_m)));
  // HET01's cover: 15 spheres of 10 m in 1 ha, 0.471.
  const int spheres =
      static_cast<int>(std::lround(0.471e4 / (std::numbers::pi * sphere_m * sphere_m)));
  const int rays = quick ? 500 : 10000, rounds = quick ? 1 : 5;
  const fs::path folder =
      fs::temp_directory_path() / ("glaswave-disc-benchmark-" + std::to_string(getpid()));
  fs::create_directories(folder);
  write_models(folder, sphere_m, leaves);
  write_trees(folder, spheres);
  const VegetationSettings discs = settings_for(folder, "sphere.def");
  const VegetationSettings gons = settings_for(folder, "sphere.obj");
  // Memory first, in children forked before this process starts any thread.
  double disc_mib = 0, gon_mib = 0, disc_load_s = 0, gon_load_s = 0;
  const bool memory =
      child_memory(discs, disc_mib, disc_load_s) && child_memory(gons, gon_mib, gon_load_s);
  const std::unique_ptr<Terrain> terrain = testing::plane_terrain(0.159);
  const Footprint footprint = testing::nadir_footprint(*terrain);
  Case disc, gon;
  disc.simulator = simulator_for(discs, *terrain, rays);
  gon.simulator = simulator_for(gons, *terrain, rays);
  tbb::task_arena one_thread(1);
  one_thread.execute([&] {
    for (int round = 0; round < rounds; ++round)
      for (Case* c : {&disc, &gon}) {
        const auto start = Clock::now();
        const double cpu_start = thread_cpu_s();
        c->record = c->simulator->simulate(footprint);
        c->cpu_s = std::min(c->cpu_s, thread_cpu_s() - cpu_start);
        c->wall_s =
            std::min(c->wall_s, std::chrono::duration<double>(Clock::now() - start).count());
      }
  });
  fs::remove_all(folder);

  std::printf(
      "disc leaves%s: %d spheres of %d leaves (radius %.1f m, disc %.2f m), %d rays, "
      "order 8, one thread\n",
      quick ? " (--quick)" : "", spheres, leaves, sphere_m, disc_radius_m, rays);
  std::printf("  %-22s %14s %14s %9s %9s %12s\n", "leaves as", "peak RSS (MiB)", "to 1st shot (s)",
              "wall (s)", "cpu (s)", "rx_energy_J");
  std::printf("  %-22s %14.1f %14.3f %9.3f %9.3f %12.4g\n", "discs", disc_mib, disc_load_s,
              disc.wall_s, disc.cpu_s, disc.record.rx_energy_J[0]);
  std::printf("  %-22s %14.1f %14.3f %9.3f %9.3f %12.4g\n", "12-gons (12 triangles)", gon_mib,
              gon_load_s, gon.wall_s, gon.cpu_s, gon.record.rx_energy_J[0]);
  std::printf("ratios (fastest of %d rounds):\n", rounds);
  std::printf("  disc shot / 12-gon shot, the thread's CPU time:  %.2f\n", disc.cpu_s / gon.cpu_s);
  std::printf("  disc shot / 12-gon shot, wall time:              %.2f\n",
              disc.wall_s / gon.wall_s);
  std::printf("  discs' peak memory / 12-gons':                   %.2f\n", disc_mib / gon_mib);
  std::printf("  the same energy returned, discs / 12-gons:       %.3f\n",
              disc.record.rx_energy_J[0] / gon.record.rx_energy_J[0]);
  const bool measured = memory && disc.cpu_s > 0 && gon.cpu_s > 0 && disc_mib > 0 && gon_mib > 0 &&
                        std::isfinite(disc.wall_s) && std::isfinite(gon.wall_s);
  std::printf(measured ? "every figure measured\n" : "a figure is missing\n");
  return measured ? 0 : 1;
}
