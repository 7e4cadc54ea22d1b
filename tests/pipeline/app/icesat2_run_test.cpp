// End to end: an ATLAS pass (the atlas preset, its photon-counting receiver) over a forest on a
// plane writes atl03.h5 and atl08.h5 beside shots.nc; the photons a shot are the few the
// mission reports, the sun at noon adds background, and the granules hold the same values for
// one thread and two.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

namespace fs = std::filesystem;

constexpr int kShots = 300;

int run_glaswave(const fs::path& config, const fs::path& out, const std::string& extra,
                 const fs::path& log) {
  const std::string command = std::string(GLASWAVE_BINARY) + " run '" + config.string() +
                              "' --out '" + out.string() + "' --quiet " + extra + " >'" +
                              log.string() + "' 2>&1";
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string bytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// 300 shots 0.7 m apart northward over a level forest (the seed's Table 1 canopy), at noon
// near the equator at an equinox: the sun 10 degrees from the zenith.
nlohmann::json atlas_pass() {
  return {
      {"seed", 3},
      {"sensor", {{"preset", "atlas"}}},
      {"simulation", {{"rays_per_shot", 300}, {"max_order", 3}}},
      {"terrain",
       {{"plane", {{"origin_lat_deg", 10.0}, {"origin_lon_deg", 0.0}, {"elevation_m", 100.0}}},
        {"soil_reflectance", 0.15}}},
      {"canopy", nlohmann::json::object()},
      {"track",
       {{"type", "pass"},
        {"start_lat_deg", 10.0},
        {"start_lon_deg", 0.0},
        {"heading_deg", 0.0},
        {"shots", kShots},
        {"spacing_m", 0.7},
        {"altitude_m", 496000.0},
        {"start_time", "2019-03-20T12:00:00Z"}}},
      {"output", {{"netcdf", true}, {"geojson", false}}},
  };
}

template <typename T>
std::vector<T> read(hid_t file, const std::string& path, hid_t type) {
  const hid_t set = H5Dopen2(file, path.c_str(), H5P_DEFAULT);
  EXPECT_GE(set, 0) << path;
  if (set < 0) return {};
  const hid_t space = H5Dget_space(set);
  std::vector<T> values(static_cast<std::size_t>(H5Sget_simple_extent_npoints(space)));
  if (!values.empty()) H5Dread(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data());
  H5Sclose(space);
  H5Dclose(set);
  return values;
}

TEST(Icesat2Run, AnAtlasPassWritesAtl03AndAtl08TheSameForAnyThreads) {
  const test_support::ScratchDir dir("glaswave_icesat2_run");
  const fs::path config = dir.path() / "atlas.json";
  std::ofstream(config) << atlas_pass().dump(2);
  ASSERT_EQ(run_glaswave(config, dir.path() / "one", "--threads 1", dir.path() / "one.txt"), 0)
      << bytes(dir.path() / "one.txt");
  ASSERT_EQ(run_glaswave(config, dir.path() / "two", "--threads 2", dir.path() / "two.txt"), 0)
      << bytes(dir.path() / "two.txt");
  for (const char* name : {"atl03.h5", "atl08.h5", "shots.nc"}) {
    ASSERT_TRUE(fs::exists(dir.path() / "one" / name)) << name;
    EXPECT_FALSE(fs::exists(dir.path() / "one" / (std::string(name) + ".part"))) << name;
  }
  // The same values (the files differ only in `history`, the command line with its --threads).
  const auto values = [&](const char* run, const char* granule, const std::string& path) {
    const hid_t f = H5Fopen((dir.path() / run / granule).c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    std::vector<double> v = read<double>(f, path, H5T_NATIVE_DOUBLE);
    H5Fclose(f);
    return v;
  };
  for (const char* path : {"/gt2l/heights/h_ph", "/gt2l/heights/lat_ph", "/gt2l/heights/delta_time",
                           "/gt2l/heights/glaswave_truth_class", "/gt2l/heights/signal_conf_ph",
                           "/gt2l/geolocation/ph_index_beg", "/gt2l/bckgrd_atlas/bckgrd_rate"})
    EXPECT_EQ(values("one", "atl03.h5", path), values("two", "atl03.h5", path)) << path;
  for (const char* path :
       {"/gt2l/land_segments/terrain/h_te_best_fit", "/gt2l/land_segments/canopy/h_canopy",
        "/gt2l/signal_photons/classed_pc_flag"})
    EXPECT_EQ(values("one", "atl08.h5", path), values("two", "atl08.h5", path)) << path;

  const hid_t file =
      H5Fopen((dir.path() / "one" / "atl03.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  const auto truth =
      read<std::uint8_t>(file, "/gt2l/heights/glaswave_truth_class", H5T_NATIVE_UINT8);
  const auto h = read<float>(file, "/gt2l/heights/h_ph", H5T_NATIVE_FLOAT);
  const auto rate = read<float>(file, "/gt2l/bckgrd_atlas/bckgrd_rate", H5T_NATIVE_FLOAT);
  H5Fclose(file);
  ASSERT_EQ(truth.size(), h.size());
  double signal = 0.0, background = 0.0;
  for (const std::uint8_t c : truth) (c == 0 ? background : signal) += 1.0;
  // A strong beam over a forest of reflectance well under 0.9: fewer signal photons a shot than
  // over ice (9.7 in the same atmosphere), but some; the sun near the zenith over a scene of a
  // few tenths' reflectance gives 0.5-5 MHz, 0.25-2.5 photons in the 500 ns window.
  EXPECT_GT(signal / kShots, 0.5);
  EXPECT_LT(signal / kShots, 9.7);
  ASSERT_EQ(rate.size(), static_cast<std::size_t>(kShots));
  EXPECT_GT(rate[0], 0.2e6);
  EXPECT_LT(rate[0], 5e6);
  EXPECT_NEAR(background / kShots, rate[0] * 500e-9, 5.0 * std::sqrt(rate[0] * 500e-9 / kShots));
  // Ground photons at the plane's 100 m: most within the pulse's reach of it (those whose light
  // met the canopy first come later, lower).
  double ground = 0.0, near_plane = 0.0;
  for (std::size_t i = 0; i < h.size(); ++i)
    if (truth[i] == 1) {
      ground += 1.0;
      if (std::abs(h[i] - 100.0) < 1.0) near_plane += 1.0;
    }
  EXPECT_GT(ground, 0.0);
  EXPECT_GT(near_plane / ground, 0.9);
}

}  // namespace
}  // namespace glaswave
