// End to end: an ATLAS pass (the atlas preset, its photon-counting receiver) over a forest on a
// plane writes atl03.h5 and atl08.h5 beside shots.nc; the photons a shot are the few the
// mission reports, the sun at noon adds background, and the granules hold the same values for
// one thread and two, for a run split inside a stretch of shots sharing one scene, and for a run
// killed half way and resumed.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "tests/pipeline/app/run_control.hpp"
#include "tests/pipeline/atlas_pass.hpp"
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
// near the equator at an equinox: the sun 10 degrees from the zenith; shots.nc written too.
nlohmann::json atlas_pass() {
  nlohmann::json pass = test_support::atlas_pass(kShots, 300, 3);
  pass["output"]["netcdf"] = true;
  return pass;
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
  // Split inside the first stretch of 256 shots, whose one scene both parts build alike.
  ASSERT_EQ(run_glaswave(config, dir.path() / "first", "--threads 2 --shots 0:131",
                         dir.path() / "first.txt"),
            0)
      << bytes(dir.path() / "first.txt");
  ASSERT_EQ(run_glaswave(config, dir.path() / "rest", "--threads 1 --shots 131:300",
                         dir.path() / "rest.txt"),
            0)
      << bytes(dir.path() / "rest.txt");
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
  // A shot's photons, whichever part of the run simulated it (the background rate and the
  // classes estimated from a run's neighbouring shots are the run's).
  for (const char* path : {"/gt2l/heights/h_ph", "/gt2l/heights/lat_ph", "/gt2l/heights/lon_ph",
                           "/gt2l/heights/delta_time", "/gt2l/heights/glaswave_truth_class"}) {
    std::vector<double> split = values("first", "atl03.h5", path);
    const std::vector<double> rest = values("rest", "atl03.h5", path);
    split.insert(split.end(), rest.begin(), rest.end());
    EXPECT_EQ(values("one", "atl03.h5", path), split) << path;
  }
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

double mean_of(const std::vector<double>& v) {
  double sum = 0.0;
  for (const double x : v) sum += x;
  return v.empty() ? std::nan("") : sum / static_cast<double>(v.size());
}

// All six beams in one run: 60 shots 0.7 m apart northward over bare level ground of reflectance
// 0.9, the sun near the zenith. Each beam flies its own track (atlas_beams: pairs 3.3 km apart, 90
// m within a pair, the weak beam 2.5 km ahead) and records its own photons (its energy, its
// channels) under the same sun; the granules hold the same values for one thread and two, and a run
// split by --shots holds the whole run's photons, shot for shot.
TEST(Icesat2Run, SixBeamsEachOnItsOwnTrackTheSameForAnyThreadsAndSplit) {
  const test_support::ScratchDir dir("glaswave_icesat2_beams");
  nlohmann::json pass = atlas_pass();
  pass.erase("canopy");
  pass["terrain"]["soil_reflectance"] = 0.9;
  pass["track"]["shots"] = 60;
  pass["sensor"]["beams"] = {"gt1l", "gt1r", "gt2l", "gt2r", "gt3l", "gt3r"};
  pass["simulation"] = {{"rays_per_shot", 100}, {"max_order", 1}};
  pass["output"]["netcdf"] = false;
  const fs::path config = dir.path() / "beams.json";
  std::ofstream(config) << pass.dump(2);
  for (const auto& [run, extra] :
       std::vector<std::pair<std::string, std::string>>{{"one", "--threads 1"},
                                                        {"two", "--threads 2"},
                                                        {"first", "--threads 2 --shots 0:25"},
                                                        {"rest", "--threads 2 --shots 25:60"}})
    ASSERT_EQ(run_glaswave(config, dir.path() / run, extra, dir.path() / (run + ".txt")), 0)
        << bytes(dir.path() / (run + ".txt"));
  // Other tracks give one beam's footprints: several beams there are refused, by check as by run.
  nlohmann::json points = pass;
  points["track"] = {{"type", "points"}, {"points", {{{"lat_deg", 10.0}, {"lon_deg", 0.0}}}}};
  const fs::path points_config = dir.path() / "points.json";
  std::ofstream(points_config) << points.dump(2);
  ASSERT_EQ(run_glaswave(points_config, dir.path() / "points", "", dir.path() / "points.txt"), 2);
  EXPECT_NE(bytes(dir.path() / "points.txt").find("/sensor/beams: several beams fly a pass only"),
            std::string::npos)
      << bytes(dir.path() / "points.txt");
  const std::string check =
      std::string(GLASWAVE_BINARY) + " check '" + points_config.string() + "' >/dev/null 2>&1";
  const int status = std::system(check.c_str());
  EXPECT_EQ(WIFEXITED(status) ? WEXITSTATUS(status) : -1, 2);

  const auto values = [&](const std::string& run, const std::string& path) {
    const hid_t f = H5Fopen((dir.path() / run / "atl03.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    std::vector<double> v = read<double>(f, path, H5T_NATIVE_DOUBLE);
    H5Fclose(f);
    return v;
  };
  const std::vector<std::string> beams = {"gt1l", "gt1r", "gt2l", "gt2r", "gt3l", "gt3r"};
  std::vector<double> photons, background, lat, lon;
  for (const std::string& beam : beams) {
    for (const char* field : {"h_ph", "lat_ph", "lon_ph", "delta_time", "glaswave_truth_class"}) {
      const std::string path = "/" + beam + "/heights/" + field;
      const std::vector<double> whole = values("one", path);
      EXPECT_EQ(whole, values("two", path)) << path;
      std::vector<double> split = values("first", path);
      const std::vector<double> rest = values("rest", path);
      split.insert(split.end(), rest.begin(), rest.end());
      EXPECT_EQ(whole, split) << path;
    }
    const std::vector<double> truth = values("one", "/" + beam + "/heights/glaswave_truth_class");
    photons.push_back(static_cast<double>(
        std::count_if(truth.begin(), truth.end(), [](double c) { return c > 0.0; })));
    background.push_back(static_cast<double>(truth.size()) - photons.back());
    lat.push_back(mean_of(values("one", "/" + beam + "/heights/lat_ph")));
    lon.push_back(mean_of(values("one", "/" + beam + "/heights/lon_ph")));
  }
  // Metres a degree at 10 N on WGS84: 110 608 of latitude, 109 640 of longitude.
  const auto east_m = [&](int a, int b) { return (lon[b] - lon[a]) * 109640.0; };
  const auto north_m = [&](int a, int b) { return (lat[b] - lat[a]) * 110608.0; };
  for (int pair = 0; pair < 3; ++pair) {
    EXPECT_NEAR(east_m(2 * pair, 2 * pair + 1), 90.0, 1.0) << beams[2 * pair];
    EXPECT_NEAR(north_m(2 * pair, 2 * pair + 1), 2500.0, 5.0) << beams[2 * pair];
    if (pair > 0) {
      EXPECT_NEAR(east_m(0, 2 * pair), 3300.0 * pair, 5.0) << beams[2 * pair];
      EXPECT_NEAR(north_m(0, 2 * pair), 0.0, 5.0) << beams[2 * pair];
    }
  }
  // The sun's background is the same light in either kind of beam (the same field of view,
  // filter and scene): strong and weak beams count it alike, to 3 standard errors.
  const double strong_background = background[0] + background[2] + background[4];
  const double weak_background = background[1] + background[3] + background[5];
  EXPECT_GT(strong_background, 100.0);
  EXPECT_NEAR(weak_background / strong_background, 1.0,
              3.0 * std::sqrt(1.0 / strong_background + 1.0 / weak_background));
  // A strong beam's shot: E T A_T rho eta / (pi R^2 h nu) = 175 uJ 0.64 0.41 m^2 0.9 0.0675 /
  // (pi 495.9 km^2 3.734e-19 J) = 9.67 photons (the field of view takes all the beam), a weak
  // one's 45/175 of it, 2.49. The pulse (0.64 ns) is far shorter than the dead time (3.2 ns): each
  // of a beam's n channels (16 strong, 4 weak) counts Poisson(mu / n) photons but records at most
  // one, so a shot records n (1 - exp(-mu / n)) photons (7.26 strong, 1.85 weak; 2.30 had the weak
  // beam 16 channels) with the variance n p (1 - p); the mean over each kind's 180 shots to 3
  // standard errors (0.27 and 0.22).
  for (const bool strong : {true, false}) {
    const double mu = strong ? 9.67 : 9.67 * 45.0 / 175.0, n = strong ? 16.0 : 4.0;
    const double p = 1.0 - std::exp(-mu / n);
    const double recorded =
        (strong ? photons[0] + photons[2] + photons[4] : photons[1] + photons[3] + photons[5]) /
        180.0;
    EXPECT_NEAR(recorded, n * p, 3.0 * std::sqrt(n * p * (1.0 - p) / 180.0))
        << (strong ? "strong" : "weak");
  }
}

// A pass killed half way and resumed writes the uninterrupted run's granules: a stretch's scene
// (built by the middle shot of the stretch before it, while the other thread goes on) depends on
// the stretch alone, and the journal keeps each finished shot's photons.
TEST(Icesat2Run, AKilledPassResumesToTheSameGranules) {
  const test_support::ScratchDir dir("glaswave_icesat2_resume");
  nlohmann::json pass = test_support::atlas_pass(3000, 30, 4);
  pass["sensor"]["beams"] = {"gt2l"};
  const fs::path config = dir.path() / "pass.json";
  std::ofstream(config) << pass.dump(2);
  const auto arguments = [&](const std::string& run) {
    return "run '" + config.string() + "' --quiet --threads 2 --out '" +
           (dir.path() / run).string() + "'";
  };
  // The uninterrupted run, and the size its journal reached (it is removed at the end).
  const pid_t pid = test_support::start_glaswave(arguments("whole"));
  std::uintmax_t journal_whole = 0;
  int status = 0;
  while (waitpid(pid, &status, WNOHANG) != pid) {
    journal_whole = std::max(journal_whole,
                             test_support::size_or_zero(dir.path() / "whole" / "glaswave.journal"));
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  ASSERT_GT(journal_whole, 0u);
  const fs::path killed = dir.path() / "killed";
  ASSERT_TRUE(test_support::kill_when(test_support::start_glaswave(arguments("killed")),
                                      killed / "glaswave.journal", journal_whole / 2))
      << "the run ended first";
  EXPECT_FALSE(fs::exists(killed / "atl03.h5"));
  ASSERT_EQ(run_glaswave(config, killed, "--threads 2 --resume", dir.path() / "resumed.txt"), 0)
      << bytes(dir.path() / "resumed.txt");
  const auto values = [&](const std::string& run, const std::string& granule,
                          const std::string& path) {
    const hid_t f = H5Fopen((dir.path() / run / granule).c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    std::vector<double> v = read<double>(f, path, H5T_NATIVE_DOUBLE);
    H5Fclose(f);
    return v;
  };
  for (const char* field : {"h_ph", "lat_ph", "lon_ph", "delta_time", "glaswave_truth_class"}) {
    const std::string path = std::string("/gt2l/heights/") + field;
    const std::vector<double> whole = values("whole", "atl03.h5", path);
    EXPECT_GT(whole.size(), 3000u) << path;
    EXPECT_EQ(values("killed", "atl03.h5", path), whole) << path;
  }
  for (const char* path :
       {"/gt2l/land_segments/terrain/h_te_best_fit", "/gt2l/land_segments/canopy/h_canopy",
        "/gt2l/signal_photons/classed_pc_flag"})
    EXPECT_EQ(values("killed", "atl08.h5", path), values("whole", "atl08.h5", path)) << path;
}

}  // namespace
}  // namespace glaswave
