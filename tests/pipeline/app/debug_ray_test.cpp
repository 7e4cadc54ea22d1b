// End to end: `glaswave run CONFIG --debug-ray SHOT:RAY` prints one ray's events, and the rays
// re-run alone one by one add up to the shot that `glaswave run` wrote.
#include <gtest/gtest.h>
#include <netcdf.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "tests/pipeline/engine/engine_test_support.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

namespace fs = std::filesystem;
using namespace test_support;

constexpr int rays = 16;

class DebugRay : public ::testing::Test {
 protected:
  void SetUp() override {
    // One shot at nadir over bare soil (0.15) on a plane sloping 8 degrees, few rays.
    nlohmann::json config = plane_shot("glas", 8.0, 0.0, rays);
    config["output"] = {{"netcdf", true}, {"footprints", false}};
    config_ = (dir_ / "plane.json").string();
    std::ofstream(config_) << config.dump(2);
  }

  ScratchDir dir_{"glaswave_debug_ray"};
  std::string config_;
};

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream stream(text);
  for (std::string line; std::getline(stream, line);) lines.push_back(line);
  return lines;
}

std::vector<std::string> words_of(const std::string& line) {
  std::vector<std::string> words;
  std::istringstream stream(line);
  for (std::string word; stream >> word;) words.push_back(word);
  return words;
}

// The ray's part of the shot's energy, per band, from the closing comment line.
std::vector<double> ray_energy_J(const std::string& output) {
  const auto at = output.find("energy (J):");
  std::istringstream stream(output.substr(at + 11));
  std::vector<double> energy;
  std::string band;
  double value;
  for (int k = 0; k < 2 && (stream >> band >> value); ++k) energy.push_back(value);
  return energy;
}

// A bare plane's single scattering is known: the beam path meets the ground and scores
// rho_s cos(slope) (PHYSICS.md section 1: a Lambertian surface of reflectance rho seen at the
// reference range weighs rho times the cosine of its tilt). A ray theta ~ 0.1 mrad off the axis
// sees the tilt change by sin(8 deg) theta and meets the ground R theta tan(8 deg) nearer or
// farther: both within 3e-5, so 1e-4.
TEST_F(DebugRay, PrintsOneLinePerEventWithTheKnownSingleScattering) {
  const CommandOutcome run = run_glaswave("run " + config_ + " --debug-ray 0:3");
  ASSERT_EQ(run.status, 0) << run.output;
  const std::vector<std::string> lines = lines_of(run.output);
  ASSERT_GE(lines.size(), 6u) << run.output;
  const std::vector<std::string> header = words_of(lines[1]);
  const std::vector<std::string> columns = {"path",        "event",  "order",   "east_m",
                                            "north_m",     "up_m",   "element", "weight_532",
                                            "weight_1064", "path_m", "bin"};
  EXPECT_EQ(header, columns);
  std::vector<std::vector<std::string>> events;
  for (std::size_t i = 2; i < lines.size(); ++i) {
    if (lines[i].rfind("#", 0) == 0) continue;
    events.push_back(words_of(lines[i]));
    EXPECT_EQ(events.back().size(), columns.size()) << lines[i];
  }
  ASSERT_GE(events.size(), 4u);
  EXPECT_EQ(events[0][0], "single");
  EXPECT_EQ(events[0][1], "enter");
  EXPECT_EQ(events[1][1], "interaction");
  EXPECT_EQ(events[1][6], "ground");
  ASSERT_EQ(events[2][1], "score");
  const double expected = 0.15 * std::cos(8.0 * M_PI / 180.0);
  EXPECT_NEAR(std::stod(events[2][7]) / expected, 1.0, 1e-4);
  EXPECT_NEAR(std::stod(events[2][8]) / expected, 1.0, 1e-4);
  // The window's bin: the reference return (2R/c, R = 600 km at nadir over a plane at height
  // 0) sits two thirds into the window, at bin floor(2 * 544 / 3) = 362 (LidarModel), and a
  // return whose way detector -> ground -> laser is path_m comes (path_m - 2R) / c later.
  const double late_ns = (std::stod(events[2][9]) - 2.0 * 600000.0) / 0.299792458;
  EXPECT_NEAR(std::stoi(events[2][10]), 362.0 + late_ns, 0.51);
  EXPECT_EQ(events[3][1], "end");
  // The ray's second path, for multiple scattering: it starts again from the top.
  EXPECT_EQ(events[4][0], "multi");
  EXPECT_EQ(events[4][1], "enter");
}

// Every ray of the shot re-run alone: their energies add up to the shot's rx_energy in
// shots.nc, to the 7 digits printed. A ray re-run with other random numbers than in the run
// would miss by the Monte Carlo noise of 16 rays.
TEST_F(DebugRay, TheRaysAddUpToTheShotOfTheRun) {
  const CommandOutcome run =
      run_glaswave("run " + config_ + " --quiet --out " + (dir_ / "out").string());
  ASSERT_EQ(run.status, 0) << run.output;
  int nc = -1, var = -1;
  double shot_J[2] = {0.0, 0.0};
  ASSERT_EQ(nc_open((dir_ / "out" / "shots.nc").c_str(), NC_NOWRITE, &nc), NC_NOERR);
  ASSERT_EQ(nc_inq_varid(nc, "rx_energy", &var), NC_NOERR);
  ASSERT_EQ(nc_get_var_double(nc, var, shot_J), NC_NOERR);
  nc_close(nc);
  double sum_J[2] = {0.0, 0.0};
  for (int ray = 0; ray < rays; ++ray) {
    const CommandOutcome traced =
        run_glaswave("run " + config_ + " --debug-ray 0:" + std::to_string(ray));
    ASSERT_EQ(traced.status, 0) << traced.output;
    const std::vector<double> energy = ray_energy_J(traced.output);
    ASSERT_EQ(energy.size(), 2u) << traced.output;
    sum_J[0] += energy[0];
    sum_J[1] += energy[1];
  }
  ASSERT_GT(shot_J[0], 0.0);
  EXPECT_NEAR(sum_J[0] / shot_J[0], 1.0, 1e-5);
  EXPECT_NEAR(sum_J[1] / shot_J[1], 1.0, 1e-5);
}

TEST_F(DebugRay, ShotsAndRaysOutsideTheRunAreRefused) {
  for (const std::string bad : {"7:0", "0:16", "0", "a:1", "-1:2"}) {
    const CommandOutcome run = run_glaswave("run " + config_ + " --debug-ray " + bad);
    EXPECT_EQ(run.status, 2) << bad << ": " << run.output;
    EXPECT_NE(run.output.find("--debug-ray"), std::string::npos) << run.output;
  }
}

}  // namespace
}  // namespace glaswave
