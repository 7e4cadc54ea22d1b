// The rt retrieval's calibration, accuracy and speed (issue 37), run by hand or by
// ./scripts/benchmark: a forward table of GEDI shots over a turbid layer 5-15 m (PAI 0-5,
// 2000 rays, 2 shots an entry; built once and kept in --table), and held-out shots of other
// seeds whose PAI is drawn uniformly over the table's range (so that a calibrated posterior's
// 90 % interval holds the truth in 90 % of them, averaged over the prior), over a plane 75 m
// up. Each alternative (the first cut's likelihood and search, the calibrated likelihood
// searched directly, in two stages, and in two stages through the principal components'
// prefilter, without the emulator, without tempering) retrieves the same shots on --threads
// threads: the 90 % interval's coverage of PAI and cover, PAI's bias and RMSE, the ground's, the
// flags, shots a second (with each alternative's speed as a ratio to the first cut's, measured in
// this one run) and CPU seconds, and how many shots' posteriors equal the exact two-stage
// search's to the bit (`same`).
// Not a test: `--quick` is the short mode that ctest runs (a small table, few shots).
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "pipeline/config/config.hpp"
#include "pipeline/engine/inputs.hpp"
#include "pipeline/products/gedi_l2a_groups.hpp"
#include "pipeline/retrieval/forward_table.hpp"
#include "pipeline/retrieval/rt_inversion.hpp"
#include "tests/pipeline/retrieval/layer_table.hpp"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using Clock = std::chrono::steady_clock;
using namespace glaswave;

json layer_configuration(int rays, int entries) {
  return test_support::layer_table_configuration({{"preset", "gedi"}}, 420000.0, rays, entries);
}

struct HeldOut {
  ShotRecord record;
  double noise_sd_W = 0.0;
};

// Shot i: its own seed, PAI (i + 1/2) / n of the range shuffled by a golden-ratio sequence,
// over a plane 75 m up; the detector off (the table's, noise-free) or on.
std::vector<HeldOut> held_out(int shots, int rays, std::uint64_t seed, int threads) {
  std::vector<HeldOut> out(shots);
  tbb::task_arena arena(threads);
  arena.execute([&] {
    tbb::parallel_for(0, shots, [&](int i) {
      json document = layer_configuration(rays, 0);
      document.erase("table");
      const double u = std::fmod(0.6180339887498949 * (i + 1) + 0.5 / shots, 1.0);
      document["canopy"]["pai"] = 5.0 * u;
      document["seed"] = seed + static_cast<std::uint64_t>(i);
      document["terrain"]["plane"]["elevation_m"] = 75.0;
      document["track"]["points"] = {{{"lat_deg", 0.01 + 0.0007 * i}, {"lon_deg", 0.0}}};
      document["detector"] = {{"enabled", false}};
      const Config config = parse_config(document);
      const auto terrain = open_terrain(config);
      const auto track = plan_track(config, *terrain);
      const auto simulator = make_shot_simulator(config, *terrain);
      out[i].record = simulator->simulate(track->footprint(0));
    });
  });
  return out;
}

RtShot measured(const ShotRecord& r) {
  RtShot shot;
  for (const auto& band : r.rx_waveform_W) shot.waveform.emplace_back(band);
  shot.axis = {1.0, r.elev_bin0_m, r.elev_lastbin_m};
  shot.noise_mean_W.assign(r.rx_waveform_W.size(), 0.0);
  shot.noise_sd_W.assign(r.rx_waveform_W.size(), 0.0);
  const std::vector<double>& w = r.rx_waveform_W[0];
  const double peak = *std::max_element(w.begin(), w.end());
  const L2aResult l2a = process_l2a({w, shot.axis, 0.0, 0.01 * peak});
  shot.ground_guess_m = l2a.groups[0].has_ground ? l2a.groups[0].elev_lowestmode_m
                                                 : std::numeric_limits<double>::quiet_NaN();
  return shot;
}

struct Figures {
  double pai_coverage = 0, cover_coverage = 0, pai_bias = 0, pai_rmse = 0, pai_sd = 0;
  double ground_bias = 0, ground_rmse = 0, ground_mad = 0;
  int ground_far = 0, ground_far_flagged = 0, flagged = 0, shots = 0;
  double shots_per_s = 0, cpu_s = 0, setup_s = 0, tempering = 0;
  int same = -1;  // shots whose result equals the reference's to the bit (-1: no reference)
};

bool same_result(const RtResult& a, const RtResult& b) {
  const auto eq = [](const RtStatistic& x, const RtStatistic& y) {
    return std::memcmp(&x, &y, sizeof(RtStatistic)) == 0;
  };
  return eq(a.pai, b.pai) && eq(a.cover, b.cover) && eq(a.canopy_height_m, b.canopy_height_m) &&
         eq(a.ground_elevation_m, b.ground_elevation_m) && eq(a.rhov_rhog, b.rhov_rhog) &&
         a.flag == b.flag && a.best_entry == b.best_entry;
}

double cpu_seconds() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

Figures evaluate(const ForwardTable& table, const RtSettings& settings,
                 const std::vector<HeldOut>& shots, int threads, std::vector<RtResult>* keep,
                 const std::vector<RtResult>* reference) {
  Figures f;
  const auto t0 = Clock::now();
  const RtInversion rt(table, settings);
  f.setup_s = std::chrono::duration<double>(Clock::now() - t0).count();
  f.tempering = rt.tempering();
  if (settings.likelihood == RtLikelihood::calibrated)
    std::printf("  noise model: v(T) = %.3g W T + %.3g T^2 (a peak of %.3g W)\n",
                rt.variance_linear_W(0), rt.variance_quadratic(0),
                *std::max_element(table.waveform_W[0][0].begin(), table.waveform_W[0][0].end()));
  std::vector<RtShot> inputs;
  for (const HeldOut& h : shots) inputs.push_back(measured(h.record));
  std::vector<RtResult> results(shots.size());
  tbb::task_arena arena(threads);
  const auto t1 = Clock::now();
  const double c1 = cpu_seconds();
  arena.execute([&] {
    tbb::parallel_for(std::size_t{0}, shots.size(),
                      [&](std::size_t i) { results[i] = rt.invert(inputs[i]); });
  });
  f.shots_per_s = shots.size() / std::chrono::duration<double>(Clock::now() - t1).count();
  f.cpu_s = cpu_seconds() - c1;
  if (reference && reference->size() == results.size()) {
    f.same = 0;
    for (std::size_t i = 0; i < results.size(); ++i)
      f.same += same_result(results[i], (*reference)[i]);
  }
  if (keep) *keep = results;
  std::vector<double> ground_errors;
  if (std::getenv("RT_DEBUG")) {
    for (double bin : {0.0, 0.25, 0.5, 0.75, 1.0, 2.0, 3.0, 4.0}) {
      const double top = bin < 1.0 ? bin + 0.25 : bin + 1.0;
      int n = 0, c = 0;
      std::vector<double> z2;
      for (std::size_t i = 0; i < shots.size(); ++i) {
        const ShotRecord& s = shots[i].record;
        if (s.pai_true < bin || s.pai_true >= top) continue;
        ++n;
        c += results[i].pai.p05 <= s.pai_true && s.pai_true <= results[i].pai.p95;
        z2.push_back(std::pow((results[i].pai.mean - s.pai_true) / results[i].pai.sd, 2));
      }
      std::sort(z2.begin(), z2.end());
      std::printf("  PAI [%.2f, %.2f): %3d shots, covered %.2f, z2 median %.2f p90 %.2f\n", bin,
                  top, n, n ? double(c) / n : 0.0, z2.empty() ? 0.0 : z2[z2.size() / 2],
                  z2.empty() ? 0.0 : z2[z2.size() * 9 / 10]);
    }
  }
  for (std::size_t i = 0; i < shots.size(); ++i) {
    const ShotRecord& s = shots[i].record;
    const RtResult& r = results[i];
    if (std::isnan(r.pai.mean)) continue;
    ++f.shots;
    const double e = r.pai.mean - s.pai_true;
    f.pai_bias += e;
    f.pai_rmse += e * e;
    f.pai_sd += r.pai.sd;
    f.pai_coverage += r.pai.p05 <= s.pai_true && s.pai_true <= r.pai.p95;
    f.cover_coverage += r.cover.p05 <= s.cover_true && s.cover_true <= r.cover.p95;
    const double g = r.ground_elevation_m.mean - s.elev_m;
    f.ground_bias += g;
    f.ground_rmse += g * g;
    ground_errors.push_back(std::abs(g));
    const bool far = std::abs(g) > 1.0;
    f.ground_far += far;
    f.ground_far_flagged += far && r.flag != 0;
    f.flagged += r.flag != 0;
  }
  const double n = std::max(1, f.shots);
  f.pai_bias /= n;
  f.pai_rmse = std::sqrt(f.pai_rmse / n);
  f.pai_sd /= n;
  f.pai_coverage /= n;
  f.cover_coverage /= n;
  f.ground_bias /= n;
  f.ground_rmse = std::sqrt(f.ground_rmse / n);
  if (!ground_errors.empty()) {
    std::nth_element(ground_errors.begin(), ground_errors.begin() + ground_errors.size() / 2,
                     ground_errors.end());
    f.ground_mad = ground_errors[ground_errors.size() / 2];
  }
  return f;
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false;
  int entries = 1000, shots = 600, rays = 2000, threads = 2;
  fs::path table_path = "retrieval_benchmark_table.nc";
  std::string only;
  int components = RtSettings{}.projection_components;
  double margin = RtSettings{}.prefilter_margin_log_likelihood;
  int exact_entries = RtSettings{}.max_exact_entries;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto next = [&] { return i + 1 < argc ? std::string(argv[++i]) : std::string(); };
    if (a == "--quick")
      quick = true;
    else if (a == "--entries")
      entries = std::stoi(next());
    else if (a == "--shots")
      shots = std::stoi(next());
    else if (a == "--rays")
      rays = std::stoi(next());
    else if (a == "--threads")
      threads = std::stoi(next());
    else if (a == "--table")
      table_path = next();
    else if (a == "--only")
      only = next();
    else if (a == "--components")
      components = std::stoi(next());
    else if (a == "--margin")
      margin = std::stod(next());
    else if (a == "--exact-entries")
      exact_entries = std::stoi(next());
  }
  if (quick) {
    entries = 64;
    shots = 12;
    rays = 1000;
    table_path = fs::temp_directory_path() / "glaswave_retrieval_benchmark_quick.nc";
    fs::remove(table_path);
  }
  ForwardTable table;
  const auto t0 = Clock::now();
  if (fs::exists(table_path)) {
    table = read_table(table_path);
    std::printf("table: read %s (%zu entries)\n", table_path.c_str(), table.entries());
  } else {
    table = build_table({layer_configuration(rays, entries), ".", threads}, {});
    write_table(table, table_path, "retrieval_benchmark");
    std::printf("table: %zu entries of %d rays built in %.1f s on %d threads\n", table.entries(),
                rays, std::chrono::duration<double>(Clock::now() - t0).count(), threads);
  }
  const auto t1 = Clock::now();
  const std::vector<HeldOut> held =
      held_out(shots, static_cast<int>(table.rays_per_shot), 987654321, threads);
  {
    double s2 = 0.0;
    for (int i = 0; i < shots; ++i) {
      const double u = std::fmod(0.6180339887498949 * (i + 1) + 0.5 / shots, 1.0);
      s2 += std::pow(held[i].record.pai_true - 5.0 * u, 2);
    }
    std::printf("held out: the truth under the beam against the configured PAI: rms %.4f\n",
                std::sqrt(s2 / shots));
  }
  std::printf(
      "held out: %d shots (PAI uniform over [0, 5], other seeds, plane 75 m up) in %.1f s\n", shots,
      std::chrono::duration<double>(Clock::now() - t1).count());

  struct Alternative {
    const char* name;
    RtSettings settings;
  };
  std::vector<Alternative> alternatives;
  {
    RtSettings first_cut;
    first_cut.likelihood = RtLikelihood::constant_sd;
    first_cut.search = RtSearch::direct;
    alternatives.push_back({"first_cut", first_cut});
    RtSettings direct;
    direct.search = RtSearch::direct;
    alternatives.push_back({"calibrated_direct", direct});
    RtSettings two_stage;
    two_stage.search = RtSearch::two_stage;
    alternatives.push_back({"calibrated_two_stage", two_stage});
    RtSettings projected;
    projected.projection_components = components;
    projected.prefilter_margin_log_likelihood = margin;
    projected.max_exact_entries = exact_entries;
    alternatives.push_back({"calibrated_projected", projected});
    RtSettings raw;
    raw.search = RtSearch::two_stage;
    raw.emulator_neighbours = 1;
    alternatives.push_back({"no_emulator", raw});
    RtSettings untempered;
    untempered.search = RtSearch::two_stage;
    untempered.tempering = 1.0;
    alternatives.push_back({"untempered", untempered});
  }
  std::printf("%-22s %6s %6s %7s %6s %6s %7s %7s %6s %5s %5s %6s %9s %6s %7s %6s %5s\n",
              "alternative", "cov90", "covC", "bias", "rmse", "sd", "g_bias", "g_rmse", "g_mad",
              "g>1m", "flag", "tau", "shots/s", "ratio", "cpu_s", "setup", "same");
  double base_speed = 0.0;
  int measured_figures = 0;
  std::vector<RtResult> reference;  // the exact two-stage search's, for `same`
  for (const Alternative& alternative : alternatives) {
    // --only a,b: the alternatives whose names hold one of these (the ratio's base is then the
    // first of them).
    bool wanted = only.empty();
    for (std::size_t from = 0; !wanted && from <= only.size();) {
      const std::size_t to = std::min(only.find(',', from), only.size());
      const std::string token = only.substr(from, to - from);
      wanted = !token.empty() && std::string(alternative.name).find(token) != std::string::npos;
      from = to + 1;
    }
    if (!wanted) continue;
    const bool is_reference = std::string(alternative.name) == "calibrated_two_stage";
    const Figures f =
        evaluate(table, alternative.settings, held, threads, is_reference ? &reference : nullptr,
                 reference.empty() ? nullptr : &reference);
    if (base_speed == 0.0) base_speed = f.shots_per_s;
    std::printf(
        "%-22s %6.3f %6.3f %+7.3f %6.3f %6.3f %+7.3f %7.3f %6.3f %2d/%-2d %5d %6.1f %9.0f %6.2f "
        "%7.2f %6.2f %5d\n",
        alternative.name, f.pai_coverage, f.cover_coverage, f.pai_bias, f.pai_rmse, f.pai_sd,
        f.ground_bias, f.ground_rmse, f.ground_mad, f.ground_far, f.ground_far_flagged, f.flagged,
        f.tempering, f.shots_per_s, f.shots_per_s / base_speed, f.cpu_s, f.setup_s, f.same);
    measured_figures += f.shots > 0 && std::isfinite(f.pai_rmse);
  }
  std::printf(
      "(cov90: the 90 %% interval holds the truth; g>1m: grounds over 1 m off / of them "
      "flagged; ratio: shots a second over the first cut's; cpu_s: CPU seconds of the process "
      "while "
      "retrieving; same: shots equal to calibrated_two_stage's to the bit, -1 before it)\n");
  if (quick) fs::remove(table_path);
  std::printf(measured_figures > 0 ? "every figure measured\n" : "a figure is missing\n");
  return 0;
}
