// ICESat-2's speed (issue 25), run by ./scripts/benchmark: whole runs (run_simulation) of one
// strong ATLAS beam (gt2l) at 10 kHz, 0.7 m between shots, over the seed's Table 1 forest and
// over bare ground on a level plane, writing atl03.h5 and atl08.h5 alone, every core; their
// shots a second against the mission's 10,000 (one beam in real time) and against each other,
// measured in this one process so that the ratios hold on a shared machine; and all six beams'
// footprints a second against 60,000 (six beams in real time). Then the shots alone
// (the engine's batch loop, nothing written) with each stretch of 256 shots sharing one scene, as
// a run does, against each shot building its own (the per-shot path every other receiver takes);
// and what the granules read (the run's simulator, make_run_shot_simulator) against every field of
// the record (make_shot_simulator's: the waveform metrics, each shot's ground fit and the beam's
// outline, as shots.nc needs them).
// Beside the wall-clock rates, the process's CPU time a shot (every thread's), which other loads
// on the machine disturb less. Last, the Monte Carlo noise of a shot's expected photons at each
// ray count, with plain and Sobol' sampling: the same footprints traced with two seeds give
// Var_MC = <(mu_1 - mu_2)^2> / 2, compared with the Poisson variance mu that the photon draw adds
// (Var_MC / mu < 0.1: the rays add under a tenth to the counts' variance).
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
#include "tests/pipeline/atlas_pass.hpp"

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// One strong beam over a level plane at 10 N, the sun 10 degrees from the zenith.
glaswave::Config atlas_config(int shots, int rays, bool forest, std::uint64_t seed,
                              bool sobol = false) {
  nlohmann::json pass = glaswave::test_support::atlas_pass(shots, rays, seed);
  pass["sensor"]["beams"] = {"gt2l"};
  if (!forest) pass["canopy"] = nullptr;
  if (sobol) pass["simulation"]["sampling"] = "sobol";
  return glaswave::parse_config(pass);
}

double cpu_s() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

// Shots a second (wall clock) and CPU milliseconds a shot of one measurement.
struct Speed {
  double shots_per_s = std::nan("");
  double cpu_ms_per_shot = std::nan("");
};

template <typename Work>
Speed measure(std::int64_t shots, Work work) {
  const auto start = Clock::now();
  const double cpu_start = cpu_s();
  if (!work()) return {};
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return {static_cast<double>(shots) / seconds,
          1e3 * (cpu_s() - cpu_start) / static_cast<double>(shots)};
}

// A whole run, its products written.
Speed run_speed(const glaswave::Config& config) {
  glaswave::RunRequest request;
  request.out_dir =
      fs::temp_directory_path() / ("glaswave-atlas-benchmark-" + std::to_string(getpid()));
  fs::remove_all(request.out_dir);
  const Speed speed = measure(config.track.shots, [&] {
    glaswave::run_simulation(config, request, {});
    return fs::exists(request.out_dir / "atl03.h5") && fs::exists(request.out_dir / "atl08.h5");
  });
  fs::remove_all(request.out_dir);
  return speed;
}

// The shots alone through the engine's batch loop, sharing their stretches' scenes or not,
// computing what the run's granules read (as a run does) or every field of the record (as
// shots.nc needs: the waveform metrics, each shot's ground fit, the beam's outline).
Speed shot_speed(const glaswave::Config& config, bool shared, bool every_field = false) {
  const auto terrain = glaswave::make_terrain(config.terrain);
  const auto track = glaswave::plan_track(config, *terrain);
  const auto simulator = every_field ? glaswave::make_shot_simulator(config, *terrain)
                                     : glaswave::make_run_shot_simulator(config, *terrain);
  if (shared) simulator->share_scenes_along(*track);
  if (simulator->shares_scenes() != shared) return {};
  std::int64_t photons = 0;
  return measure(track->size(), [&] {
    glaswave::simulate_records(*simulator, *track, 0, track->size(), 0,
                               [&](std::int64_t, const glaswave::ShotRecord& shot) {
                                 photons += static_cast<std::int64_t>(shot.photon_class.size());
                               },
                               {});
    return photons > 0;
  });
}

// Var_MC / mu of a strong beam's expected signal photons a shot over the forest at `rays`: one
// forest, the transport's rays drawn with two seeds.
double monte_carlo_over_poisson(int shots, int rays, bool sobol) {
  const glaswave::Config one = atlas_config(shots, rays, true, 1, sobol);
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
  std::printf("  %5d rays %-6s: mu %.2f photons a shot, Var_MC %.3f, Var_MC / mu %.3f\n", rays,
              sobol ? "sobol" : "random", mean, variance, variance / mean);
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
  std::printf("%-28s %6s %6s %10s %14s %12s\n", "case", "shots", "rays", "shots/s", "of 10,000/s",
              "CPU ms/shot");
  std::vector<double> figures;
  for (const bool forest : {true, false})
    for (const int rays : {30, 300}) {
      const Speed speed = run_speed(atlas_config(shots, rays, forest, 1));
      std::printf("%-28s %6d %6d %10.1f %13.2f%% %12.3f\n",
                  forest ? "Table 1 forest" : "bare ground", shots, rays, speed.shots_per_s,
                  100.0 * speed.shots_per_s / 10000.0, speed.cpu_ms_per_shot);
      figures.push_back(speed.shots_per_s);
    }
  std::printf("ratios: forest 300/30 rays time %.2f; forest/bare time at 30 rays %.2f\n",
              figures[0] / figures[1], figures[2] / figures[0]);
  // All six beams over the forest, each beam's footprints on its own ground track: real time is
  // 60,000 footprints a second (the target on a 16-core machine).
  {
    nlohmann::json pass = glaswave::test_support::atlas_pass(shots, 30, 1);
    pass["sensor"]["beams"] = {"gt1l", "gt1r", "gt2l", "gt2r", "gt3l", "gt3r"};
    const Speed speed = run_speed(glaswave::parse_config(pass));
    std::printf(
        "six beams: %d shots x 6 over the Table 1 forest, 30 rays: %.1f footprints/s, "
        "%.2f%% of 60,000/s, %.3f CPU ms a footprint\n",
        shots, 6.0 * speed.shots_per_s, 100.0 * 6.0 * speed.shots_per_s / 60000.0,
        speed.cpu_ms_per_shot / 6.0);
    figures.push_back(speed.shots_per_s);
  }
  std::printf(
      "the shots alone (nothing written), 30 rays: a stretch's scene shared against each "
      "shot's own\n");
  std::printf("%-28s %12s %12s %10s %12s %12s\n", "case", "shared /s", "own /s", "speed-up",
              "shared ms", "own ms");
  for (const bool forest : {true, false}) {
    const glaswave::Config config = atlas_config(shots, 30, forest, 1);
    const Speed shared = shot_speed(config, true), own = shot_speed(config, false);
    std::printf("%-28s %12.1f %12.1f %9.2fx %12.3f %12.3f\n",
                forest ? "Table 1 forest" : "bare ground", shared.shots_per_s, own.shots_per_s,
                shared.shots_per_s / own.shots_per_s, shared.cpu_ms_per_shot, own.cpu_ms_per_shot);
    figures.insert(figures.end(), {shared.shots_per_s, own.shots_per_s});
  }
  std::printf(
      "the shots alone, 30 rays, shared scenes: what the granules read against every field of "
      "the record (shots.nc's)\n");
  std::printf("%-28s %12s %12s %10s %12s %12s\n", "case", "granules /s", "every /s", "speed-up",
              "granules ms", "every ms");
  for (const bool forest : {true, false}) {
    const glaswave::Config config = atlas_config(shots, 30, forest, 1);
    const Speed granules = shot_speed(config, true), every = shot_speed(config, true, true);
    std::printf("%-28s %12.1f %12.1f %9.2fx %12.3f %12.3f\n",
                forest ? "Table 1 forest" : "bare ground", granules.shots_per_s, every.shots_per_s,
                granules.shots_per_s / every.shots_per_s, granules.cpu_ms_per_shot,
                every.cpu_ms_per_shot);
    figures.insert(figures.end(), {granules.shots_per_s, every.shots_per_s});
  }
  std::printf("Monte Carlo noise of the expected photons (forest, %d shots, two seeds):\n",
              mc_shots);
  for (const bool sobol : {false, true})
    for (const int rays : {10, 20, 30, 100, 300})
      figures.push_back(monte_carlo_over_poisson(mc_shots, rays, sobol));
  std::printf("peak resident memory of this process: %.0f MiB\n", peak_resident_MiB());
  bool all = true;
  for (const double f : figures) all = all && std::isfinite(f);
  std::printf(all ? "every figure measured\n" : "a figure is missing\n");
  return all ? 0 : 1;
}
