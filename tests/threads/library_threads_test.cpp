// The library from several threads at once (issue 28): threads that each check a configuration,
// run it into a folder of their own (a GeoTIFF DEM read through GDAL and PROJ, a forest,
// shots.nc through libnetcdf and HDF5, the footprints through OGR) and read their shots.nc back,
// all together, end with the products of one run alone. ./scripts/test --sanitize builds this
// target again with ThreadSanitizer (build-tsan/), where a data race between the threads fails
// it.
#include <gtest/gtest.h>
#include <netcdf.h>

#include <barrier>
#include <filesystem>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "core/netcdf_lock.hpp"
#include "pipeline/config/config.hpp"
#include "pipeline/engine/run.hpp"
#include "pipeline/products/netcdf_writer.hpp"
#include "tests/scratch_dir.hpp"
#include "tests/terrain/dem_fixture.hpp"

namespace glaswave {
namespace {

namespace fs = std::filesystem;

constexpr int kThreads = 3;
constexpr int kRounds = 2;

// Hills in UTM zone 32N about (46 N, 8 E), 10 m cells over 1 km.
void write_dem(const fs::path& file) {
  int zone = 0;
  bool north = true;
  double x = 0, y = 0;
  GeographicLib::UTMUPS::Forward(46.0, 8.0, zone, north, x, y, 32);
  testing::RasterSpec spec;
  spec.crs = "EPSG:32632";
  spec.width = spec.height = 100;
  spec.geotransform = {std::floor(x - 500.0), 10.0, 0.0, std::floor(y + 500.0), 0.0, -10.0};
  testing::write_raster(file, spec, [](int col, int row, int) {
    return 800.0 + 20.0 * std::sin(col / 15.0) * std::cos(row / 20.0) + 0.3 * row;
  });
}

Config small_run(const fs::path& dem) {
  return parse_config({
      {"seed", 7},
      {"sensor", {{"preset", "glas"}}},
      {"simulation", {{"rays_per_shot", 60}, {"max_order", 3}}},
      {"terrain", {{"dem", dem.string()}}},
      {"canopy", {{"pai", 2.0}, {"cover", 0.6}, {"crown_radius_m", 4.0}}},
      {"track", {{"start_lat_deg", 45.999}, {"start_lon_deg", 8.0}, {"shots", 3}}},
  });
}

// shots.nc's received waveforms, read back as a user does (under the library's lock).
std::vector<double> waveforms(const fs::path& file) {
  std::lock_guard<std::mutex> lock(netcdf_library_mutex());
  quiet_hdf5_in_this_thread();
  int id = -1, variable = -1, dims[3] = {0, 0, 0};
  EXPECT_EQ(nc_open(file.c_str(), NC_NOWRITE, &id), NC_NOERR) << file;
  EXPECT_EQ(nc_inq_varid(id, "rx_waveform", &variable), NC_NOERR);
  EXPECT_EQ(nc_inq_vardimid(id, variable, dims), NC_NOERR);
  std::size_t count = 1;
  for (int dim : dims) {
    std::size_t length = 0;
    nc_inq_dimlen(id, dim, &length);
    count *= length;
  }
  std::vector<double> values(count);
  EXPECT_EQ(nc_get_var_double(id, variable, values.data()), NC_NOERR);
  nc_close(id);
  return values;
}

TEST(LibraryThreads, RunsTogetherGiveTheProductsOfOneRunAlone) {
  test_support::ScratchDir dir("glaswave_threads");
  const fs::path dem = dir.path() / "hills.tif";
  write_dem(dem);
  const Config config = small_run(dem);
  RunRequest alone;
  alone.threads = 1;
  alone.out_dir = dir.path() / "alone";
  ASSERT_EQ(run_simulation(config, alone, nullptr).shots, 3);
  const std::vector<double> expected = waveforms(alone.out_dir / "shots.nc");
  ASSERT_FALSE(expected.empty());

  std::barrier start(kThreads);
  std::mutex failures_mutex;
  std::vector<std::string> failures;
  auto work = [&](int thread) {
    for (int round = 0; round < kRounds; ++round) {
      start.arrive_and_wait();  // the threads begin each round together
      try {
        // Each thread parses its own configuration, as separate callers would.
        const Config mine = small_run(dem);
        check_inputs(mine);
        RunRequest request;
        request.threads = 1;
        request.out_dir = dir.path() / ("t" + std::to_string(thread) + "r" + std::to_string(round));
        run_simulation(mine, request, nullptr);
        if (waveforms(request.out_dir / "shots.nc") != expected)
          throw std::runtime_error(request.out_dir.string() + ": other waveforms");
        if (!fs::is_regular_file(request.out_dir / "footprints.geojson"))
          throw std::runtime_error(request.out_dir.string() + ": no footprints");
      } catch (const std::exception& error) {
        std::lock_guard<std::mutex> lock(failures_mutex);
        failures.push_back(error.what());
      }
    }
  };
  std::vector<std::thread> threads;
  for (int thread = 0; thread < kThreads; ++thread) threads.emplace_back(work, thread);
  for (std::thread& thread : threads) thread.join();
  EXPECT_TRUE(failures.empty()) << failures.front();
}

}  // namespace
}  // namespace glaswave
