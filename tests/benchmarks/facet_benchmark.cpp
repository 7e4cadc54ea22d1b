// The facet trees' benchmark that ./scripts/benchmark runs (issue 24): the resident memory of a
// 1 ha plot of 500 instanced trees of one model of 100 016 triangles (100 000 leaves and a trunk),
// read from an OBJ as `glaswave run` reads it, and the cost of a shot over those facets against a
// shot over turbid crowns of the same plant area in the same places (ellipsoids of the model's
// crown, leaf size the facets' side), at the seed's settings (10 000 rays, order 8, Table 2's
// beam at nadir from 600 km, one thread). Both in one process, so that the ratio holds on a
// shared machine; each shot's wall time and its thread's CPU time (the part of a shared core it
// really had), and the CPU time a ray query costs. Not a test: `--quick` (10 000 triangles, 50
// trees, 500 rays) is the short mode that ctest runs; `--leaves N` puts the same leaf area in N
// leaves (what the cost owes to the model's triangle count).
#include <tbb/task_arena.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
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

constexpr double crown_radius_m = 2.5, crown_half_height_m = 4.0, crown_base_m = 6.0;
// The full model's leaves; `--leaves N` gives the same leaf area in N leaves of another side.
constexpr int full_leaves = 100000;
constexpr double full_leaf_side_m = 0.04;

// The model: `leaves` equilateral leaves (spherical normals, centres uniform in the crown's
// ellipsoid) and an 8-sided trunk, as OBJ and MTL.
void write_model(const fs::path& folder, int leaves, double leaf_side_m) {
  std::ofstream(folder / "tree.mtl") << "newmtl leaf\nnewmtl wood\n";
  std::ofstream obj(folder / "tree.obj");
  obj << "mtllib tree.mtl\n";
  std::mt19937_64 bits(7);
  auto uniform = [&bits] { return static_cast<double>(bits() >> 11) * 0x1.0p-53; };
  const double circumradius = leaf_side_m / std::sqrt(3.0);
  for (int k = 0; k < leaves; ++k) {
    Vec3 c;
    do c = {2 * uniform() - 1, 2 * uniform() - 1, 2 * uniform() - 1};
    while (dot(c, c) > 1.0);
    c = {crown_radius_m * c[0], crown_radius_m * c[1],
         crown_base_m + crown_half_height_m * (1.0 + c[2])};
    const double cos_t = 2 * uniform() - 1, phi = 2 * std::numbers::pi * uniform();
    const double sin_t = std::sqrt(1 - cos_t * cos_t);
    const Vec3 n{sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t};
    const Vec3 helper = std::abs(n[2]) < 0.9 ? Vec3{0, 0, 1} : Vec3{1, 0, 0};
    const Vec3 u = normalized(cross(n, helper)), v = cross(n, u);
    for (int corner = 0; corner < 3; ++corner) {
      const double a = 2 * std::numbers::pi * corner / 3.0;
      const Vec3 p = c + circumradius * (std::cos(a) * u + std::sin(a) * v);
      obj << "v " << p[0] << ' ' << p[1] << ' ' << p[2] << '\n';
    }
  }
  for (int k = 0; k < 8; ++k)
    for (double z : {0.0, crown_base_m + crown_half_height_m})
      obj << "v " << 0.1 * std::cos(k * std::numbers::pi / 4) << ' '
          << 0.1 * std::sin(k * std::numbers::pi / 4) << ' ' << z << '\n';
  obj << "usemtl leaf\n";
  for (int k = 0; k < leaves; ++k)
    obj << "f " << 3 * k + 1 << ' ' << 3 * k + 2 << ' ' << 3 * k + 3 << '\n';
  obj << "usemtl wood\n";
  const int first = 3 * leaves + 1;
  for (int k = 0; k < 8; ++k) {
    const int a = first + 2 * k, b = a + 1, c = first + 2 * ((k + 1) % 8), d = c + 1;
    obj << "f " << a << ' ' << c << ' ' << d << "\nf " << a << ' ' << d << ' ' << b << '\n';
  }
}

// Trees on a jittered grid over 100 m x 100 m about the plane's origin.
void write_trees(const fs::path& folder, int trees) {
  std::ofstream csv(folder / "trees.csv");
  csv << "x,y,model,rotation_deg,scale\n";
  std::mt19937_64 bits(11);
  auto uniform = [&bits] { return static_cast<double>(bits() >> 11) * 0x1.0p-53; };
  const int side = static_cast<int>(std::ceil(std::sqrt(trees)));
  const double step_m = 100.0 / side;
  for (int k = 0; k < trees; ++k)
    csv << -50.0 + step_m * (k % side + uniform()) << ',' << -50.0 + step_m * (k / side + uniform())
        << ",tree," << 360.0 * uniform() << ",1\n";
}

// Turbid crowns where the facet trees stand: the model's crown ellipsoid, of the density that
// gives each crown the model's leaf area.
class CrownsOfFacets : public VegetationSource {
 public:
  CrownsOfFacets(const FacetSource& facets, double leaf_area_m2, double leaf_side_m)
      : facets_(facets),
        leaf_side_m_(leaf_side_m),
        density_(leaf_area_m2 / (4.0 / 3.0 * std::numbers::pi * crown_radius_m * crown_radius_m *
                                 crown_half_height_m)) {}
  RegionVegetation grow(const VegetationRegion& region) const override {
    const RegionVegetation trees = facets_.grow(region);
    RegionVegetation grown;
    grown.geometry.trunks.max_height_m = -std::numeric_limits<double>::infinity();
    for (const FacetInstance& tree : trees.geometry.facets) {
      Crown crown;
      crown.base_m = tree.foot_m + Vec3{0.0, 0.0, crown_base_m};
      crown.radius_m = crown_radius_m;
      crown.half_height_m = crown_half_height_m;
      crown.area_density_m2_m3 = density_;
      grown.geometry.crowns.push_back(crown);
    }
    Foliage leaves = trees.materials.front();
    leaves.leaf_angles = &angles_;
    leaves.leaf_size_m = leaf_side_m_;
    grown.materials = {leaves};
    return grown;
  }

 private:
  const FacetSource& facets_;
  double leaf_side_m_;
  double density_;
  LeafAngles angles_{LeafAngleDistribution::spherical, 57.3};
};

// A shot's cost: its wall time, and its thread's CPU time (the shot runs on the calling thread),
// which leaves out the time other processes of a shared machine hold the core.
struct ShotCost {
  double wall_s = 1e300, cpu_s = 1e300;
  std::int64_t queries = 0;  // Embree's and the crowns' ray queries of the last shot
  void keep_fastest(const ShotCost& other) {
    wall_s = std::min(wall_s, other.wall_s);
    cpu_s = std::min(cpu_s, other.cpu_s);
    queries = other.queries;
  }
};

double thread_cpu_s() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

ShotCost shot_cost(const ShotSimulator& simulator, const Footprint& footprint, ShotRecord& out) {
  ShotCost cost;
  const auto start = Clock::now();
  const double cpu_start_s = thread_cpu_s();
  out = simulator.simulate(footprint, &cost.queries);
  cost.cpu_s = thread_cpu_s() - cpu_start_s;
  cost.wall_s = std::chrono::duration<double>(Clock::now() - start).count();
  return cost;
}

}  // namespace

int main(int argc, char** argv) {
  const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
  const int leaves = quick                                               ? 10000
                     : argc > 2 && std::strcmp(argv[1], "--leaves") == 0 ? std::atoi(argv[2])
                                                                         : full_leaves;
  if (leaves < 1) {
    std::fprintf(stderr, "facet_benchmark: --leaves needs a positive number\n");
    return 2;
  }
  const double leaf_side_m =
      quick ? full_leaf_side_m : full_leaf_side_m * std::sqrt(double{full_leaves} / leaves);
  const int trees = quick ? 50 : 500, rays = quick ? 500 : 10000;
  const int rounds = quick ? 1 : 7;  // the fastest kept: a shared machine's load falls on some
  const fs::path folder =
      fs::temp_directory_path() / ("glaswave-facet-benchmark-" + std::to_string(getpid()));
  fs::create_directories(folder);
  write_model(folder, leaves, leaf_side_m);
  write_trees(folder, trees);
  const std::unique_ptr<Terrain> terrain = testing::plane_terrain(0.3);
  const double rss_start = status_mib("VmRSS");

  VegetationSettings settings;
  settings.plane = PlaneSettings{testing::kLat0, testing::kLon0, 0.0, 0.0, 0.0};
  settings.canopy.kind = "facets";
  settings.canopy.facet_trees_file = (folder / "trees.csv").string();
  settings.canopy.facet_models = {{"tree", (folder / "tree.obj").string()}};
  settings.canopy.facet_materials = {{"leaf", {0.45}, {0.45}, true}, {"wood", {0.3}, {0}, false}};
  auto facets = std::make_unique<FacetSource>(settings);
  const FacetSource& plot = *facets;
  const double leaf_area_m2 = leaves * std::sqrt(3.0) / 4.0 * leaf_side_m * leaf_side_m;
  ShotSettings shot = testing::shot_settings(0.3, rays);
  shot.transport.max_order = 8;
  const ShotSimulator over_facets(shot, *terrain, std::move(facets),
                                  make_receiver(testing::receiver_settings(shot, "waveform")));
  const ShotSimulator over_crowns(shot, *terrain,
                                  std::make_unique<CrownsOfFacets>(plot, leaf_area_m2, leaf_side_m),
                                  make_receiver(testing::receiver_settings(shot, "waveform")));
  // The same with one ray: what a shot costs before its rays (its scene, its truth).
  ShotSettings one_ray = shot;
  one_ray.transport.rays = 1;
  const ShotSimulator facets_alone(one_ray, *terrain, std::make_unique<FacetSource>(settings),
                                   make_receiver(testing::receiver_settings(one_ray, "waveform")));
  const ShotSimulator crowns_alone(
      one_ray, *terrain, std::make_unique<CrownsOfFacets>(plot, leaf_area_m2, leaf_side_m),
      make_receiver(testing::receiver_settings(one_ray, "waveform")));
  const Footprint footprint = testing::nadir_footprint(*terrain);
  ShotCost facet, crown, facet_fixed, crown_fixed;
  ShotRecord unused;
  ShotRecord facet_record, crown_record;
  tbb::task_arena one_thread(1);
  one_thread.execute([&] {
    for (int round = 0; round < rounds; ++round) {
      facet.keep_fastest(shot_cost(over_facets, footprint, facet_record));
      crown.keep_fastest(shot_cost(over_crowns, footprint, crown_record));
      facet_fixed.keep_fastest(shot_cost(facets_alone, footprint, unused));
      crown_fixed.keep_fastest(shot_cost(crowns_alone, footprint, unused));
    }
  });
  const double rss_plot = status_mib("VmRSS") - rss_start, peak = status_mib("VmHWM");
  fs::remove_all(folder);

  std::printf("facet trees%s: %d trees of %d triangles on 1 ha, %d rays, order 8, one thread\n",
              quick ? " (--quick)" : "", trees, leaves + 16, rays);
  std::printf(
      "  resident memory of the plot (model, instances, a shot's scene): %.1f MiB "
      "(process peak %.1f MiB)\n",
      rss_plot, peak);
  std::printf("  %-14s %8s %8s %13s %9s %9s %9s %8s %12s\n", "shot over", "wall (s)", "cpu (s)",
              "cpu 1 ray (s)", "queries", "us/query", "pai_true", "cover", "rx_energy_J");
  auto row = [](const char* name, const ShotCost& shot, const ShotCost& fixed,
                const ShotRecord& record) {
    // The rays' CPU time over their queries (surfaces, crowns' spans, shadow rays).
    const double us_per_query = 1e6 * (shot.cpu_s - fixed.cpu_s) / (shot.queries - fixed.queries);
    std::printf("  %-14s %8.3f %8.3f %13.4f %9lld %9.3f %9.3f %8.3f %12.4g\n", name, shot.wall_s,
                shot.cpu_s, fixed.cpu_s, static_cast<long long>(shot.queries), us_per_query,
                record.pai_true, record.cover_true, record.rx_energy_J[0]);
  };
  row("facets", facet, facet_fixed, facet_record);
  row("turbid crowns", crown, crown_fixed, crown_record);
  std::printf("ratios (fastest of %d rounds):\n", rounds);
  std::printf("  shot over facets / over turbid crowns, wall time:         %.2f\n",
              facet.wall_s / crown.wall_s);
  std::printf("  the same, the thread's CPU time:                          %.2f\n",
              facet.cpu_s / crown.cpu_s);
  std::printf("  the same, less each shot's CPU time at 1 ray (the rays):  %.2f\n",
              (facet.cpu_s - facet_fixed.cpu_s) / (crown.cpu_s - crown_fixed.cpu_s));
  const bool measured = facet.cpu_s > 0 && crown.cpu_s > 0 && rss_plot > 0 &&
                        std::isfinite(facet.wall_s) && std::isfinite(crown.wall_s);
  std::printf(measured ? "every figure measured\n" : "a figure is missing\n");
  return measured ? 0 : 1;
}
