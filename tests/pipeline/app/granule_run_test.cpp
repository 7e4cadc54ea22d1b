// End to end: a `granule` track simulates one shot per footprint of a GEDI L2A granule, and
// shots.nc carries the granule's shot numbers, times and positions; faults are exit status 3.
#include <gtest/gtest.h>
#include <netcdf.h>
#include <sys/wait.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tests/footprints/granule_files.hpp"
#include "tests/pipeline/engine/engine_test_support.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

namespace fs = std::filesystem;

int run_glaswave(const fs::path& config, const fs::path& out, const fs::path& log) {
  const std::string command = std::string(GLASWAVE_BINARY) + " run '" + config.string() +
                              "' --out '" + out.string() + "' >'" + log.string() + "' 2>&1";
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string text_of(const fs::path& file) {
  std::ifstream in(file);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// Two beams near (0, 0) over the plane; BEAM0000's middle footprint is a fill value.
void write_granule(const fs::path& file) {
  testing::Hdf5Writer h5(file);
  h5.uint64s("BEAM0000/shot_number", {10000000001ULL, 10000000002ULL, 10000000003ULL});
  h5.doubles("BEAM0000/lat_lowestmode", {0.0, testing::gedi_fill, 0.0005});
  h5.doubles("BEAM0000/lon_lowestmode", {0.0, testing::gedi_fill, 0.0001});
  h5.doubles("BEAM0000/delta_time", {5.0e7, 5.0e7 + 0.0083, 5.0e7 + 0.0166});
  h5.uint64s("BEAM0101/shot_number", {10101000001ULL});
  h5.doubles("BEAM0101/lat_lowestmode", {-0.0003});
  h5.doubles("BEAM0101/lon_lowestmode", {0.0002});
  h5.doubles("BEAM0101/delta_time", {5.0e7 + 1.0});
}

nlohmann::json granule_config(const std::string& file) {
  nlohmann::json config = test_support::plane_shot("gedi", 0.0, 0.0, 200);
  config["track"] = {{"type", "granule"}, {"file", file}, {"altitude_m", 420000.0}};
  config["output"] = {{"netcdf", true}, {"footprints", false}};
  return config;
}

template <typename T>
std::vector<T> variable(int nc, const char* name, std::size_t n) {
  int var = -1;
  EXPECT_EQ(nc_inq_varid(nc, name, &var), NC_NOERR) << name;
  std::vector<T> values(n);
  if constexpr (std::is_same_v<T, double>)
    EXPECT_EQ(nc_get_var_double(nc, var, values.data()), NC_NOERR);
  else
    EXPECT_EQ(nc_get_var_longlong(nc, var, reinterpret_cast<long long*>(values.data())), NC_NOERR);
  return values;
}

TEST(GranuleRun, ShotsNcCarriesTheGranulesShotNumbersTimesAndPositions) {
  const test_support::ScratchDir dir("glaswave_granule_run");
  write_granule(dir.path() / "GEDI02_A.h5");
  const fs::path config = dir.path() / "granule.json";
  std::ofstream(config) << granule_config("GEDI02_A.h5").dump(2);  // relative to the config
  const fs::path out = dir.path() / "out";
  ASSERT_EQ(run_glaswave(config, out, dir.path() / "log.txt"), 0)
      << text_of(dir.path() / "log.txt");

  int nc = -1;
  ASSERT_EQ(nc_open((out / "shots.nc").c_str(), NC_NOWRITE, &nc), NC_NOERR);
  int dim = -1;
  std::size_t n = 0;
  ASSERT_EQ(nc_inq_dimid(nc, "shot", &dim), NC_NOERR);
  ASSERT_EQ(nc_inq_dimlen(nc, dim, &n), NC_NOERR);
  ASSERT_EQ(n, 3u);
  const auto shot = variable<std::int64_t>(nc, "shot", n);
  const auto number = variable<std::int64_t>(nc, "shot_number", n);
  const auto time = variable<double>(nc, "time", n);
  const auto lat = variable<double>(nc, "lat", n);
  const auto lon = variable<double>(nc, "lon", n);
  nc_close(nc);
  const std::int64_t numbers[] = {10000000001LL, 10000000003LL, 10101000001LL};
  const double lats[] = {0.0, 0.0005, -0.0003}, lons[] = {0.0, 0.0001, 0.0002};
  const double times[] = {5.0e7, 5.0e7 + 0.0166, 5.0e7 + 1.0};
  for (std::size_t i = 0; i < n; ++i) {
    EXPECT_EQ(shot[i], static_cast<std::int64_t>(i));
    EXPECT_EQ(number[i], numbers[i]);
    EXPECT_NEAR(time[i], 568036800.0 + times[i], 1e-6);
    EXPECT_NEAR(lat[i], lats[i], 1e-6);
    EXPECT_NEAR(lon[i], lons[i], 1e-6);
  }
}

TEST(GranuleRun, AMissingFileOrBeamIsExitStatus3NamingIt) {
  const test_support::ScratchDir dir("glaswave_granule_run");
  write_granule(dir.path() / "GEDI02_A.h5");
  const fs::path config = dir.path() / "granule.json";
  nlohmann::json c = granule_config("GEDI02_A.h5");
  c["track"]["beams"] = {"BEAM1011"};
  std::ofstream(config) << c.dump(2);
  const fs::path log = dir.path() / "log.txt";
  EXPECT_EQ(run_glaswave(config, dir.path() / "out", log), 3) << text_of(log);
  EXPECT_NE(text_of(log).find("GEDI02_A.h5: BEAM1011"), std::string::npos) << text_of(log);

  std::ofstream(config) << granule_config("absent.h5").dump(2);
  EXPECT_EQ(run_glaswave(config, dir.path() / "out2", log), 3) << text_of(log);
  EXPECT_NE(text_of(log).find("absent.h5"), std::string::npos) << text_of(log);
}

}  // namespace
}  // namespace glaswave
