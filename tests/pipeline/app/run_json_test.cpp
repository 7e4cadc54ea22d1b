// End to end: `glaswave run --json` prints the run's summary as one JSON object on stdout, here
// for the gedi preset over bare level ground, whose received energy is checked against the
// closed form of PHYSICS.md section 1 computed from GEDI's published numbers.
#include <gtest/gtest.h>
#include <netcdf.h>
#include <sys/wait.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <string>

#include "tests/pipeline/engine/engine_test_support.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

namespace fs = std::filesystem;

struct Streams {
  int status;
  std::string out, err;
};

// The built command with stdout and stderr kept apart.
Streams run_apart(const std::string& arguments, const fs::path& err_file) {
  const std::string command =
      std::string(GLASWAVE_BINARY) + " " + arguments + " 2>'" + err_file.string() + "'";
  FILE* pipe = popen(command.c_str(), "r");
  std::string out;
  std::array<char, 4096> buffer;
  while (std::fgets(buffer.data(), buffer.size(), pipe)) out += buffer.data();
  const int status = pclose(pipe);
  std::ostringstream err;
  err << std::ifstream(err_file).rdbuf();
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out, err.str()};
}

// One GEDI shot at nadir from 420 km over level Lambertian ground (0.15), with a second shot
// a little way off so that the summary counts more than one.
nlohmann::json gedi_over_plane() {
  nlohmann::json config = test_support::plane_shot("gedi", 0.0, 0.0, 10000);
  config["track"]["altitude_m"] = 420000.0;
  config["track"]["points"] = {{{"lat_deg", 0.0}, {"lon_deg", 0.0}},
                               {{"lat_deg", 0.001}, {"lon_deg", 0.0}}};
  config["output"] = {{"netcdf", true}, {"footprints", false}};
  return config;
}

TEST(RunJson, GediOverPlanePrintsOneJsonObjectAndTheClosedFormEnergy) {
  const test_support::ScratchDir dir("glaswave_run_json");
  const fs::path config = dir.path() / "gedi.json";
  std::ofstream(config) << gedi_over_plane().dump(2);
  const fs::path out = dir.path() / "out";
  const Streams run = run_apart("run '" + config.string() + "' --out '" + out.string() + "' --json",
                                dir.path() / "stderr.txt");
  ASSERT_EQ(run.status, 0) << run.out << run.err;

  // stdout is exactly one line, one JSON object, and no summary text.
  ASSERT_FALSE(run.out.empty());
  EXPECT_EQ(run.out.find('\n'), run.out.size() - 1) << run.out;
  const nlohmann::json summary = nlohmann::json::parse(run.out);
  ASSERT_TRUE(summary.is_object());
  EXPECT_EQ(summary.size(), 8u) << summary.dump();
  EXPECT_EQ(summary.at("shots"), 2);
  EXPECT_EQ(summary.at("shots_flagged"), 0);
  EXPECT_GT(summary.at("wall_s").get<double>(), 0.0);
  EXPECT_NEAR(summary.at("shots_per_s").get<double>(), 2.0 / summary.at("wall_s").get<double>(),
              1e-6 * summary.at("shots_per_s").get<double>());
  EXPECT_GT(summary.at("ray_queries").get<std::int64_t>(), 0);
  EXPECT_GT(summary.at("ray_queries_per_s").get<double>(), 0.0);
  EXPECT_TRUE(summary.at("vertical_datum").is_string());
  EXPECT_FALSE(summary.at("vertical_datum").get<std::string>().empty());
  EXPECT_EQ(summary.at("out_dir"), out.string());
  EXPECT_EQ(run.out.find("glaswave:"), std::string::npos);
  EXPECT_EQ(run.err.find("glaswave: error"), std::string::npos) << run.err;

  // PHYSICS.md section 1: E = E_t T A_T rho_s cos(alpha) f_fov / (pi R^2), with
  // f_fov = 1 - exp(-ifov^2 / (8 sigma^2)), from GEDI's published numbers: 10 mJ (a full-power
  // laser), an 0.8 m telescope, a 300 urad field of view, a 25 m 1/e^2 footprint from 420 km
  // (sigma = 25 / (4 * 420 km)); the round-trip transmission 0.9 is the preset's choice.
  const double pi = std::numbers::pi;
  const double sigma_rad = 25.0 / (4.0 * 420000.0);
  const double f_fov = 1.0 - std::exp(-300e-6 * 300e-6 / (8.0 * sigma_rad * sigma_rad));
  const double area_m2 = pi * 0.4 * 0.4;
  int nc = -1, var = -1;
  ASSERT_EQ(nc_open((out / "shots.nc").c_str(), NC_NOWRITE, &nc), NC_NOERR);
  double range_m[2] = {}, energy_J[2] = {};
  ASSERT_EQ(nc_inq_varid(nc, "range_m", &var), NC_NOERR);
  ASSERT_EQ(nc_get_var_double(nc, var, range_m), NC_NOERR);
  ASSERT_EQ(nc_inq_varid(nc, "rx_energy", &var), NC_NOERR);  // (shot, band), one band
  ASSERT_EQ(nc_get_var_double(nc, var, energy_J), NC_NOERR);
  nc_close(nc);
  EXPECT_NEAR(range_m[0], 420000.0, 0.01);
  for (int shot = 0; shot < 2; ++shot) {
    const double expected_J =
        10e-3 * 0.9 * area_m2 * 0.15 * f_fov / (pi * range_m[shot] * range_m[shot]);
    // The tolerance of the bare-ground tests (bare_ground_physics_test.cpp).
    EXPECT_NEAR(energy_J[shot] / expected_J, 1.0, 0.005) << "shot " << shot;
  }
}

TEST(RunJson, WithoutJsonTheSummaryIsALineOfText) {
  const test_support::ScratchDir dir("glaswave_run_json");
  const fs::path config = dir.path() / "gedi.json";
  nlohmann::json document = gedi_over_plane();
  document["simulation"]["rays_per_shot"] = 200;
  std::ofstream(config) << document.dump(2);
  const Streams run = run_apart(
      "run '" + config.string() + "' --out '" + (dir.path() / "out").string() + "' --quiet",
      dir.path() / "stderr.txt");
  ASSERT_EQ(run.status, 0) << run.out << run.err;
  EXPECT_EQ(run.out.rfind("glaswave: 2 shots in", 0), 0u) << run.out;
}

}  // namespace
}  // namespace glaswave
