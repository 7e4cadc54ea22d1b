// What the engine and app tests share: a track simulated shot by shot through ShotSimulator, the
// built glaswave command run as a user runs it, and the moments of a waveform.
#pragma once

#include <sys/wait.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "footprints/track.hpp"
#include "pipeline/engine/inputs.hpp"

namespace glaswave::test_support {

// The command-line tests' base: one shot of the glas preset over a plane at (46 N, 8 E), 100
// rays, no canopy; each merges its changes in (merge_patch).
inline nlohmann::json one_glas_shot() {
  return {
      {"sensor", {{"preset", "glas"}}},
      {"simulation", {{"rays_per_shot", 100}}},
      {"terrain", {{"plane", {{"origin_lat_deg", 46.0}, {"origin_lon_deg", 8.0}}}}},
      {"canopy", nullptr},
      {"track", {{"start_lat_deg", 46.0}, {"start_lon_deg", 8.0}, {"shots", 1}}},
  };
}

// One shot of a points track aiming at the origin (0, 0) from 600 km, tilted off nadir toward
// the east, over bare Lambertian soil (0.15) on a plane facing east with the given slope.
inline nlohmann::json plane_shot(const std::string& preset, double slope_deg, double off_nadir_deg,
                                 std::int64_t rays) {
  return {
      {"seed", 7},
      {"sensor", {{"preset", preset}}},
      {"simulation", {{"rays_per_shot", rays}}},
      {"terrain",
       {{"plane",
         {{"origin_lat_deg", 0.0},
          {"origin_lon_deg", 0.0},
          {"elevation_m", 0.0},
          {"slope_deg", slope_deg},
          {"aspect_deg", 90.0}}},
        {"soil_reflectance", 0.15}}},
      {"canopy", nullptr},
      {"track",
       {{"type", "points"},
        {"points", {{{"lat_deg", 0.0}, {"lon_deg", 0.0}}}},
        {"altitude_m", 600000.0},
        {"off_nadir_deg", off_nadir_deg},
        {"pointing_azimuth_deg", 90.0}}},
      {"output", {{"netcdf", false}, {"footprints", false}}},
  };
}

struct SimulatedTrack {
  Config config;
  std::vector<Footprint> footprints;
  std::vector<ShotRecord> records;
  std::vector<double> bin_time_ns;  // bin centres after the return from range_m
};

// Every shot of the configuration's track.
inline SimulatedTrack simulate_track(Config config) {
  SimulatedTrack run{std::move(config), {}, {}, {}};
  const auto terrain = open_terrain(run.config);
  const Track track(run.config.track, *terrain);
  run.footprints = track.footprints(0, track.size());
  const std::unique_ptr<ShotSimulator> made = make_shot_simulator(run.config, *terrain);
  const ShotSimulator& simulator = *made;
  for (const Footprint& footprint : run.footprints)
    run.records.push_back(simulator.simulate(footprint));
  run.bin_time_ns = simulator.lidar().bin_time_ns();
  return run;
}

inline SimulatedTrack simulate_track(const nlohmann::json& document) {
  return simulate_track(parse_config(document));
}

struct CommandOutcome {
  int status;
  std::string output;  // stdout and stderr together
};

// Runs a shell command line, stdout and stderr together.
inline CommandOutcome run_command(const std::string& command) {
  FILE* pipe = popen(command.c_str(), "r");
  std::string output;
  std::array<char, 4096> buffer;
  while (std::fgets(buffer.data(), buffer.size(), pipe)) output += buffer.data();
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

inline CommandOutcome run_glaswave(const std::string& arguments) {
  return run_command(std::string(GLASWAVE_BINARY) + " " + arguments + " 2>&1");
}

// A nadir shot over a layer of PAI `pai` and depth 10 m sitting on level soil.
inline nlohmann::json layer_shot(double pai, double leaf_size_m, double rho, double tau,
                                 double soil, int max_order, std::int64_t rays) {
  return {
      {"seed", 5},
      {"sensor",
       {{"preset", "north2010"},
        {"bands",
         {{{"name", "1064"},
           {"wavelength_nm", 1064},
           {"pulse_energy_mJ", 72},
           {"atmos_transmission_roundtrip", 0.9}}}}}},
      {"simulation", {{"rays_per_shot", rays}, {"max_order", max_order}}},
      {"terrain", {{"plane", {{"elevation_m", 0.0}}}, {"soil_reflectance", soil}}},
      {"canopy",
       {{"crown_shape", "layer"},
        {"pai", pai},
        {"lad", "spherical"},
        {"crown_base_m", {0.0, 0.0}},
        {"crown_half_height_m", 5.0},
        {"green_fraction", 1.0},
        {"bark_fraction", 0.0},
        {"leaf_size_m", leaf_size_m},
        {"leaf_reflectance", rho},
        {"leaf_transmittance", tau},
        {"dbh_m", 0.0}}},
      {"track", {{"type", "points"}, {"points", {{{"lat_deg", 0.0}, {"lon_deg", 0.0}}}}}},
      {"output", {{"netcdf", false}, {"footprints", false}, {"per_order", true}}},
  };
}

struct Moments {
  double mean_ns, rms_ns;
};

// Power-weighted mean time and RMS width of a waveform.
inline Moments waveform_moments(const std::vector<double>& power_W,
                                const std::vector<double>& time_ns) {
  double sum = 0, first = 0, second = 0;
  for (std::size_t i = 0; i < power_W.size(); ++i) {
    sum += power_W[i];
    first += power_W[i] * time_ns[i];
  }
  const double mean = first / sum;
  for (std::size_t i = 0; i < power_W.size(); ++i)
    second += power_W[i] * (time_ns[i] - mean) * (time_ns[i] - mean);
  return {mean, std::sqrt(second / sum)};
}

}  // namespace glaswave::test_support
