// ICESat-2's speed (issue 25), run by ./scripts/benchmark: whole runs (run_simulation) of one
// strong ATLAS beam (gt2l) at 10 kHz, 0.7 m between shots, over the seed's Table 1 forest and
// over bare ground on a level plane, writing atl03.h5 and atl08.h5 alone, every core; their
// shots a second against the mission's 10,000 (one beam in real time) and against each other,
// measured in this one process so that the ratios hold on a shared machine. Beside them, the
// Monte Carlo noise of a shot's expected photons at each ray count: the same footprints traced
// with two seeds give Var_MC = <(mu_1 - mu_2)^2> / 2, compared with the Poisson variance mu that
// the photon draw adds (Var_MC / mu < 0.1: the rays add under a tenth to the counts' variance).
// Not a test: `--quick` is the short mode that ctest runs.
#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "footprints/track.hpp"
#include "pipeline/engine/inputs.hpp"
#include "pipeline/engine/run.hpp"

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// One strong beam over a level plane at 10 N, the sun 10 degrees from the zenith.
glaswave::Config atlas_config(int shots, int rays, bool forest, std::uint64_t seed) {
  nlohmann::json document = {
      {"seed", seed},
      {"sensor", {{"preset", "atlas"}, {"beams", {"gt2l"}}}},
      {"simulation", {{"rays_per_shot", rays}, {"max_order", 3}}},
      {"terrain",
       {{"plane", {{"origin_lat_deg", 10.0}, {"origin_lon_deg", 0.0}, {"elevation_m", 100.0}}},
        {"soil_reflectance", 0.15}}},
      {"canopy", forest ? nlohmann::json::object() : nlohmann::json()},  // {}: Table 1
      {"track",
       {{"type", "pass"},
        {"start_lat_deg", 10.0},
        {"start_lon_deg", 0.0},
        {"heading_deg", 0.0},
        {"shots", shots},
        {"spacing_m", 0.7},
        {"altitude_m", 496000.0},
        {"start_time", "2019-03-20T12:00:00Z"}}},
      {"output", {{"netcdf", false}, {"geojson", false}}},
  };
  return glaswave::parse_config(document);
}

double shots_per_s(const glaswave::Config& config) {
  glaswave::RunRequest request;
  request.out_dir =
      fs::temp_directory_path() / ("glaswave-atlas-benchmark-" + std::to_string(getpid()));
  fs::remove_all(request.out_dir);
  const auto start = Clock::now();
  const glaswave::RunSummary summary = glaswave::run_simulation(config, request, {});
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  const bool written =
      fs::exists(request.out_dir / "atl03.h5") && fs::exists(request.out_dir / "atl08.h5");
  fs::remove_all(request.out_dir);
  return written ? static_cast<double>(summary.shots) / seconds : std::nan("");
}

// Var_MC / mu of a strong beam's expected signal photons a shot over the forest at `rays`: one
// forest, the transport's rays drawn with two seeds.
double monte_carlo_over_poisson(int shots, int rays) {
  const glaswave::Config one = atlas_config(shots, rays, true, 1);
  const auto terrain = glaswave::make_terrain(one.terrain);
  const glaswave::Track track(one.track, *terrain);
  const auto first = glaswave::make_shot_simulator(one, *terrain);
  glaswave::ShotSettings reseeded = glaswave::shot_settings(one);
  reseeded.transport.seed = 2;
  const auto second = std::make_unique<glaswave::ShotSimulator>(
      reseeded, *terrain, glaswave::grow_vegetation(one),
      glaswave::make_receiver(glaswave::receiver_settings(one)));
  // Expected photons = energy x efficiency / (h c / 532 nm).
  const double photons_per_J =
      one.sensor.photon_efficiency / (6.62607015e-34 * 299792458.0 / 532e-9);
  double mean = 0.0, squares = 0.0;
  for (const glaswave::Footprint& footprint : track.footprints(0, shots)) {
    const double a = first->simulate(footprint).rx_energy_J.at(0) * photons_per_J;
    const double b = second->simulate(footprint).rx_energy_J.at(0) * photons_per_J;
    mean += 0.5 * (a + b);
    squares += (a - b) * (a - b);
  }
  mean /= shots;
  const double variance = squares / (2.0 * shots);
  std::printf("  %5d rays: mu %.2f photons a shot, Var_MC %.3f, Var_MC / mu %.3f\n", rays, mean,
              variance, variance / mean);
  return variance / mean;
}

double peak_resident_MiB() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;
}

}  // namespace

int main(int argc, char** argv) {
  const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
  if (argc > 1 && !quick) {
    std::fprintf(stderr, "usage: %s [--quick]\n", argv[0]);
    return 2;
  }
  const int shots = quick ? 100 : 3000, mc_shots = quick ? 10 : 100;
  std::printf(
      "ICESat-2: one strong beam, 0.7 m between shots, atl03.h5 and atl08.h5 written, "
      "every core\n");
  std::printf("%-28s %6s %6s %10s %14s\n", "case", "shots", "rays", "shots/s", "of 10,000/s");
  std::vector<double> figures;
  for (const bool forest : {true, false})
    for (const int rays : {30, 300}) {
      const double rate = shots_per_s(atlas_config(shots, rays, forest, 1));
      std::printf("%-28s %6d %6d %10.1f %13.2f%%\n", forest ? "Table 1 forest" : "bare ground",
                  shots, rays, rate, 100.0 * rate / 10000.0);
      figures.push_back(rate);
    }
  std::printf("ratios: forest 300/30 rays time %.2f; forest/bare time at 30 rays %.2f\n",
              figures[0] / figures[1], figures[2] / figures[0]);
  std::printf("Monte Carlo noise of the expected photons (forest, %d shots, two seeds):\n",
              mc_shots);
  for (const int rays : {30, 100, 300}) figures.push_back(monte_carlo_over_poisson(mc_shots, rays));
  std::printf("peak resident memory of this process: %.0f MiB\n", peak_resident_MiB());
  bool all = true;
  for (const double f : figures) all = all && std::isfinite(f);
  std::printf(all ? "every figure measured\n" : "a figure is missing\n");
  return all ? 0 : 1;
}
