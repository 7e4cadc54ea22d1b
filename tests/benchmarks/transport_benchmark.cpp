// Transport benchmark: shots/s and ray queries/s of a pass over bare ground (the baseline) and
// over the seed's base forest (Tables 1 and 2), on one thread and on every core, all measured in
// this run so that the ratios hold on a shared machine. Not a test: run it with
// build/tests/transport_benchmark [shots] [rays_per_shot].
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>

#include "footprints/track.hpp"
#include "pipeline/engine/shot_simulation.hpp"

namespace {

struct Figures {
  double shots_per_s;
  double queries_per_s;
};

Figures measure(const glaswave::Config& config, int threads) {
  const auto terrain = glaswave::make_terrain(config.terrain);
  const glaswave::Track track(config.track, *terrain);
  const auto footprints = track.footprints(0, track.size());
  const glaswave::ShotSimulator simulator(config, *terrain);
  tbb::task_arena arena(threads);
  std::vector<std::int64_t> queries(footprints.size(), 0);
  const auto start = std::chrono::steady_clock::now();
  arena.execute([&] {
    tbb::parallel_for(std::size_t{0}, footprints.size(),
                      [&](std::size_t i) { simulator.simulate(footprints[i], &queries[i]); });
  });
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::int64_t total = 0;
  for (std::int64_t q : queries) total += q;
  return {footprints.size() / seconds, total / seconds};
}

}  // namespace

int main(int argc, char** argv) {
  const int shots = argc > 1 ? std::atoi(argv[1]) : 40;
  const int rays = argc > 2 ? std::atoi(argv[2]) : 10000;
  nlohmann::json document = {
      {"seed", 1},
      {"sensor", {{"preset", "north2010"}}},
      {"simulation", {{"rays_per_shot", rays}}},
      {"terrain",
       {{"plane", {{"origin_lat_deg", 45.0}, {"origin_lon_deg", 7.0}, {"slope_deg", 5.0}}}}},
      {"canopy", nullptr},
      {"track",
       {{"type", "pass"},
        {"start_lat_deg", 45.0},
        {"start_lon_deg", 7.0},
        {"shots", shots},
        {"spacing_m", 172.0}}},
  };
  const glaswave::Config bare = glaswave::parse_config(document);
  document["canopy"] = nlohmann::json::object();  // Table 1
  const glaswave::Config forest = glaswave::parse_config(document);
  const int cores = tbb::this_task_arena::max_concurrency();

  std::printf("glaswave transport benchmark: %d shots, %d rays a shot, %d cores\n", shots, rays,
              cores);
  std::printf("%-24s %8s %12s %16s\n", "case", "threads", "shots/s", "ray queries/s");
  const Figures bare_one = measure(bare, 1), bare_all = measure(bare, cores);
  const Figures forest_one = measure(forest, 1), forest_all = measure(forest, cores);
  auto row = [](const char* name, int threads, const Figures& f) {
    std::printf("%-24s %8d %12.1f %16.3g\n", name, threads, f.shots_per_s, f.queries_per_s);
  };
  row("bare ground (baseline)", 1, bare_one);
  row("bare ground", cores, bare_all);
  row("base forest", 1, forest_one);
  row("base forest", cores, forest_all);
  std::printf("forest / bare, shots/s (1 thread): %.3f\n",
              forest_one.shots_per_s / bare_one.shots_per_s);
  std::printf("thread scaling, forest shots/s (%d / 1): %.2f\n", cores,
              forest_all.shots_per_s / forest_one.shots_per_s);
  return 0;
}
