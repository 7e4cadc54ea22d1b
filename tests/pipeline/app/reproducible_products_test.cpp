// End to end: two identical runs with SOURCE_DATE_EPOCH set write every product byte for byte
// the same (NetCDF, GeoJSON, GeoPackage, the GEDI, GLAS and ICESat-2 granules), and the
// products' date_created is that time.
#include <gtest/gtest.h>
#include <netcdf.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tests/pipeline/atlas_pass.hpp"
#include "tests/pipeline/engine/engine_test_support.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

namespace fs = std::filesystem;

std::string bytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::string text_attribute(const fs::path& file, const char* name) {
  int nc = -1;
  std::size_t length = 0;
  if (nc_open(file.c_str(), NC_NOWRITE, &nc) != NC_NOERR) return "(no file)";
  std::string text;
  if (nc_inq_attlen(nc, NC_GLOBAL, name, &length) == NC_NOERR) {
    text.resize(length);
    nc_get_att_text(nc, NC_GLOBAL, name, text.data());
  } else {
    text = "(absent)";
  }
  nc_close(nc);
  return text;
}

// Sets an environment variable for one test, and restores it.
class Environment {
 public:
  Environment(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    if (value)
      setenv(name, value, 1);
    else
      unsetenv(name);
  }
  ~Environment() {
    if (old_)
      setenv(name_, old_->c_str(), 1);
    else
      unsetenv(name_);
  }

 private:
  const char* name_;
  std::optional<std::string> old_;
};

// Runs `config` into DIR/out twice (the same command line), the first run's products moved to
// DIR/first; returns the product names and whether each is the same bytes.
struct Reruns {
  std::vector<std::string> names, differ;
};
Reruns rerun(const fs::path& dir, const nlohmann::json& config) {
  const fs::path file = dir / "config.json";
  std::ofstream(file) << config.dump(2);
  const std::string command = "run " + file.string() + " --out " + (dir / "out").string();
  const auto first = test_support::run_glaswave(command);
  EXPECT_EQ(first.status, 0) << first.output;
  fs::rename(dir / "out", dir / "first");
  const auto second = test_support::run_glaswave(command);
  EXPECT_EQ(second.status, 0) << second.output;
  Reruns r;
  for (const auto& entry : fs::directory_iterator(dir / "out")) {
    if (!entry.is_regular_file()) continue;
    const std::string name = entry.path().filename().string();
    r.names.push_back(name);
    if (bytes(entry.path()) != bytes(dir / "first" / name)) r.differ.push_back(name);
  }
  return r;
}

bool has(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

nlohmann::json glas_pass() {
  return {
      {"seed", 7},
      {"sensor", {{"preset", "glas"}}},
      {"simulation", {{"rays_per_shot", 300}}},
      {"terrain",
       {{"plane",
         {{"origin_lat_deg", 46.0},
          {"origin_lon_deg", 8.0},
          {"elevation_m", 900.0},
          {"slope_deg", 8.0}}}}},
      {"canopy", nlohmann::json::object()},
      {"track",
       {{"type", "pass"},
        {"start_lat_deg", 46.0},
        {"start_lon_deg", 8.0},
        {"heading_deg", 350.0},
        {"shots", 4},
        {"spacing_m", 172.0}}},
      {"output",
       {{"netcdf", true},
        {"footprints", true},
        {"plots", false},
        {"gedi_l1b", true},
        {"gedi_l2a", true},
        {"glah01", true},
        {"glah14", true}}},
  };
}

TEST(ReproducibleProducts, TwoRunsWithSourceDateEpochWriteTheSameBytes) {
  const test_support::ScratchDir dir("glaswave_reproducible");
  // 1700000000 s after 1970-01-01T00:00:00Z is 2023-11-14T22:13:20Z (19675 days and 80000 s).
  const Environment epoch("SOURCE_DATE_EPOCH", "1700000000");

  fs::create_directories(dir.path() / "glas");
  const Reruns glas = rerun(dir.path() / "glas", glas_pass());
  for (const char* name :
       {"shots.nc", "footprints.geojson", "gedi_l1b.h5", "gedi_l2a.h5", "glah01.h5", "glah14.h5"})
    EXPECT_TRUE(has(glas.names, name)) << name;
  EXPECT_TRUE(glas.differ.empty()) << glas.differ.front();
  EXPECT_EQ(text_attribute(dir.path() / "glas" / "out" / "shots.nc", "date_created"),
            "2023-11-14T22:13:20.000000Z");
  EXPECT_EQ(text_attribute(dir.path() / "glas" / "out" / "shots.nc", "stats_wall_s"), "(absent)");

  nlohmann::json gpkg = glas_pass();
  gpkg["output"] = {{"netcdf", false}, {"footprints", true}, {"footprints_format", "GPKG"}};
  fs::create_directories(dir.path() / "gpkg");
  const Reruns footprints = rerun(dir.path() / "gpkg", gpkg);
  EXPECT_TRUE(has(footprints.names, "footprints.gpkg"));
  EXPECT_TRUE(footprints.differ.empty()) << footprints.differ.front();

  fs::create_directories(dir.path() / "atlas");
  const Reruns atlas = rerun(dir.path() / "atlas", test_support::atlas_pass(40, 30, 3));
  for (const char* name : {"atl03.h5", "atl08.h5"}) EXPECT_TRUE(has(atlas.names, name)) << name;
  EXPECT_TRUE(atlas.differ.empty()) << atlas.differ.front();
}

// The check above can fail: without SOURCE_DATE_EPOCH the NetCDF product says when it was made,
// to the microsecond, and how long the run took, so two runs differ.
TEST(ReproducibleProducts, WithoutSourceDateEpochTheNetcdfProductDiffers) {
  const test_support::ScratchDir dir("glaswave_reproducible_clock");
  const Environment epoch("SOURCE_DATE_EPOCH", nullptr);
  nlohmann::json config = glas_pass();
  config["output"] = {{"netcdf", true}, {"footprints", false}};
  const Reruns r = rerun(dir.path(), config);
  EXPECT_TRUE(has(r.differ, "shots.nc"));
  EXPECT_NE(text_attribute(dir.path() / "out" / "shots.nc", "stats_wall_s"), "(absent)");
}

TEST(ReproducibleProducts, AMalformedSourceDateEpochIsRefused) {
  const test_support::ScratchDir dir("glaswave_reproducible_bad");
  const Environment epoch("SOURCE_DATE_EPOCH", "1700000000.5");
  nlohmann::json config = glas_pass();
  config["output"] = {{"netcdf", true}, {"footprints", false}};
  const fs::path file = dir.path() / "config.json";
  std::ofstream(file) << config.dump(2);
  const auto outcome = test_support::run_glaswave("run " + file.string() + " --out " +
                                                  (dir.path() / "out").string());
  EXPECT_EQ(outcome.status, 2) << outcome.output;
  EXPECT_NE(outcome.output.find("SOURCE_DATE_EPOCH: must be whole seconds"), std::string::npos)
      << outcome.output;
  EXPECT_FALSE(fs::exists(dir.path() / "out" / "shots.nc"));
}

}  // namespace
}  // namespace glaswave
