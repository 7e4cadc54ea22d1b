// `glaswave retrieve` on GEDI L1B granules as a user runs it: glaswave's own gedi_l1b.h5 from a
// small run (its L2B the same as from the run's shots.nc, its truth carried through), a
// hand-made minimal file in the real GEDI01_B layout with its GEDI02_A beside it (the L2B
// closed form through the whole chain), and malformed granules refused with one line naming
// the file and the dataset.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <netcdf.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <numbers>

#include "core/hdf5_file.hpp"
#include "core/netcdf_lock.hpp"
#include "tests/pipeline/engine/engine_test_support.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

using nlohmann::json;
using test_support::CommandOutcome;
using test_support::run_glaswave;
using test_support::ScratchDir;
namespace fs = std::filesystem;

std::vector<double> nc_variable(const fs::path& file, const char* name) {
  int nc = -1, var = -1, dims[NC_MAX_VAR_DIMS], rank = 0;
  std::vector<double> values;
  if (nc_open(file.c_str(), NC_NOWRITE, &nc) != NC_NOERR) return values;
  if (nc_inq_varid(nc, name, &var) == NC_NOERR && nc_inq_varndims(nc, var, &rank) == NC_NOERR &&
      nc_inq_vardimid(nc, var, dims) == NC_NOERR) {
    std::size_t count = 1;
    for (int d = 0; d < rank; ++d) {
      std::size_t length = 0;
      nc_inq_dimlen(nc, dims[d], &length);
      count *= length;
    }
    values.resize(count);
    nc_get_var_double(nc, var, values.data());
  }
  nc_close(nc);
  return values;
}

std::vector<double> h5_dataset(const fs::path& file, const std::string& path) {
  std::lock_guard lock(netcdf_library_mutex());
  const Hdf5Reader reader(file);
  std::vector<double> values;
  EXPECT_TRUE(reader.has(path)) << path;
  if (reader.has(path)) reader.read(path, values);
  return values;
}

// glaswave's gedi_l1b.h5 beside shots.nc from one run of a turbid layer 5-15 m over a plane at
// 40 m: retrieve on either gives the same L2A and L2B (counts and W differ by a scale, to which
// cover and PAI are blind; float32 rounds the counts), and the L1B's glaswave_truth gives the
// same truth as shots.nc.
TEST(RetrieveGedi, GlaswavesOwnL1bGivesWhatItsShotsGive) {
  const ScratchDir dir("glaswave_retrieve_gedi_own");
  json track_points = json::array();
  for (int i = 0; i < 4; ++i) track_points.push_back({{"lat_deg", 0.001 * i}, {"lon_deg", 0.0}});
  const json config = {
      {"sensor", {{"preset", "gedi"}}},
      {"simulation", {{"rays_per_shot", 1000}}},
      {"terrain",
       {{"plane", {{"origin_lat_deg", 0.0}, {"origin_lon_deg", 0.0}, {"elevation_m", 40.0}}},
        {"soil_reflectance", 0.3}}},
      {"canopy",
       {{"crown_shape", "layer"},
        {"crown_base_m", {5.0, 5.0}},
        {"crown_half_height_m", 5.0},
        {"dbh_m", 0.0},
        {"pai", 1.5},
        {"cover", 1.0}}},
      {"track", {{"type", "points"}, {"points", track_points}, {"altitude_m", 420000.0}}},
      {"output", {{"footprints", false}, {"gedi_l1b", true}}},
  };
  std::ofstream(dir.path() / "pass.json") << config.dump(2);
  const CommandOutcome run = run_glaswave("run " + (dir.path() / "pass.json").string() +
                                          " --quiet --out " + (dir.path() / "pass").string());
  ASSERT_EQ(run.status, 0) << run.output;
  const fs::path l1b = dir.path() / "pass" / "gedi_l1b.h5";
  const CommandOutcome from_l1b = run_glaswave(
      "retrieve " + l1b.string() + " --quiet --json --out " + (dir.path() / "from_l1b").string());
  ASSERT_EQ(from_l1b.status, 0) << from_l1b.output;
  EXPECT_EQ(json::parse(from_l1b.output)["l2b_granule"],
            (dir.path() / "from_l1b" / "gedi_l2b.h5").string());
  const CommandOutcome from_shots =
      run_glaswave("retrieve " + (dir.path() / "pass" / "shots.nc").string() + " --quiet --out " +
                   (dir.path() / "from_shots").string());
  ASSERT_EQ(from_shots.status, 0) << from_shots.output;
  EXPECT_FALSE(fs::exists(dir.path() / "from_shots" / "gedi_l2b.h5"));  // GEDI L1B input only

  const fs::path a = dir.path() / "from_l1b" / "retrieval.nc";
  const fs::path b = dir.path() / "from_shots" / "retrieval.nc";
  for (const char* name :
       {"cover_gedi_l2b", "pai_gedi_l2b", "canopy_height_gedi_l2a", "ground_elevation_gedi_l2a",
        "pai_true", "cover_true", "canopy_height_true", "ground_elevation_true"}) {
    const std::vector<double> x = nc_variable(a, name), y = nc_variable(b, name);
    ASSERT_EQ(x.size(), 4u) << name;
    ASSERT_EQ(y.size(), 4u) << name;
    for (int i = 0; i < 4; ++i) {
      EXPECT_TRUE(std::isfinite(x[i])) << name << " " << i;
      EXPECT_NEAR(x[i], y[i], 1e-3 * std::max(1.0, std::abs(y[i]))) << name << " " << i;
    }
  }
  // gedi_l2b.h5 holds retrieval.nc's L2B, beam by beam (one beam here: BEAM0101).
  const fs::path granule = dir.path() / "from_l1b" / "gedi_l2b.h5";
  const std::vector<double> cover = h5_dataset(granule, "BEAM0101/cover");
  const std::vector<double> shots = h5_dataset(granule, "BEAM0101/shot_number");
  const std::vector<double> numbers = nc_variable(a, "shot_number");
  const std::vector<double> cover_nc = nc_variable(a, "cover_gedi_l2b");
  ASSERT_EQ(cover.size(), 4u);
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(shots[i], numbers[i]);
    EXPECT_NEAR(cover[i], cover_nc[i], 1e-6);
  }
  EXPECT_EQ(h5_dataset(granule, "BEAM0101/pai_z").size(), 4u * 30u);
}

// A minimal GEDI01_B in the real layout (the dictionary's names and dtypes, release 1's
// geolocation/degrade), each waveform 200 counts of noise mean under a canopy of area 12000
// (counts x bins) 150 bins above a ground of area 8000, bins 0.15 m apart: Pgap = 1 - 12000 /
// (12000 + 1.5 x 8000) = 0.5, cover 0.5 and, at nadir, PAI -2 ln 0.5.
struct L1bFile {
  int bins = 400;
  bool skip_elevation_bin0 = false;
  bool short_noise = false;
  bool start_past_end = false;
};

constexpr double kGroundElevation = 100.0, kBinM = 0.15;
constexpr int kGroundBin = 300;

void write_l1b(const fs::path& path, const L1bFile& spec) {
  std::lock_guard lock(netcdf_library_mutex());
  Hdf5Writer f(path);
  const std::vector<std::pair<std::string, std::vector<std::uint64_t>>> beams = {
      {"BEAM0000", {10000000001}}, {"BEAM0101", {10101000001, 10101000002}}};
  for (const auto& [g, numbers] : beams) {
    const std::size_t n = numbers.size();
    std::vector<float> rx;
    std::vector<std::uint64_t> start;
    std::vector<std::uint16_t> count;
    for (std::size_t i = 0; i < n; ++i) {
      start.push_back(rx.size() + 1 + (spec.start_past_end && i == 1 ? 5 : 0));
      count.push_back(static_cast<std::uint16_t>(spec.bins));
      for (int k = 0; k < spec.bins; ++k) {
        const auto gauss = [&](double area, double mu, double sigma) {
          return area / (sigma * std::sqrt(2 * std::numbers::pi)) *
                 std::exp(-0.5 * std::pow((k - mu) / sigma, 2));
        };
        rx.push_back(static_cast<float>(200.0 + gauss(12000.0, kGroundBin - 150, 8.0) +
                                        gauss(8000.0, kGroundBin, 6.0)));
      }
    }
    f.write(g + "/shot_number", numbers);
    f.write(g + "/rxwaveform", rx);
    f.write(g + "/rx_sample_start_index", start);
    f.write(g + "/rx_sample_count", count);
    f.write(g + "/noise_mean_corrected", std::vector<double>(spec.short_noise ? n - 1 : n, 200.0));
    f.write(g + "/noise_stddev_corrected", std::vector<double>(n, 2.0));
    f.write(g + "/beam", std::vector<std::uint16_t>(n, g == "BEAM0000" ? 0 : 5));
    f.write(g + "/delta_time", std::vector<double>(n, 4.0e7));
    const double top = kGroundElevation + kGroundBin * kBinM;
    if (!spec.skip_elevation_bin0)
      f.write(g + "/geolocation/elevation_bin0", std::vector<double>(n, top));
    f.write(g + "/geolocation/elevation_lastbin",
            std::vector<double>(n, top - (spec.bins - 1) * kBinM));
    f.write(g + "/geolocation/latitude_bin0", std::vector<double>(n, 1.0));
    f.write(g + "/geolocation/latitude_lastbin", std::vector<double>(n, 1.0));
    f.write(g + "/geolocation/longitude_bin0", std::vector<double>(n, 2.0));
    f.write(g + "/geolocation/longitude_lastbin", std::vector<double>(n, 2.0));
    f.write(g + "/geolocation/degrade", std::vector<std::int8_t>(n, 0));
    f.write(g + "/geolocation/local_beam_elevation",
            std::vector<float>(n, static_cast<float>(std::numbers::pi / 2)));
  }
  f.close();
}

// GEDI02_A for BEAM0101's shots only: its group a1, its ground and sensitivity.
void write_l2a(const fs::path& path) {
  std::lock_guard lock(netcdf_library_mutex());
  Hdf5Writer f(path);
  const std::string g = "BEAM0101";
  f.write(g + "/shot_number", std::vector<std::uint64_t>{10101000001, 10101000002});
  f.write(g + "/elev_lowestmode", std::vector<float>(2, static_cast<float>(kGroundElevation)));
  f.write(g + "/elev_highestreturn",
          std::vector<float>(2, static_cast<float>(kGroundElevation + 25.0)));
  f.write(g + "/quality_flag", std::vector<std::uint8_t>{1, 0});
  f.write(g + "/sensitivity", std::vector<float>(2, 0.93f));
  f.write(g + "/selected_algorithm", std::vector<std::uint8_t>(2, 1));
  f.write(g + "/rh", std::vector<float>(2 * 101, 0.0f), {}, {2, 101});
  f.close();
}

TEST(RetrieveGedi, RealLayoutL1bWithItsL2aGivesTheClosedForm) {
  const ScratchDir dir("glaswave_retrieve_gedi_real");
  const fs::path l1b = dir.path() / "GEDI01_B_minimal.h5", l2a = dir.path() / "GEDI02_A_minimal.h5";
  write_l1b(l1b, {});
  write_l2a(l2a);
  // The kind from the layout, not the name: the L2A first, named as nothing in particular.
  const fs::path l2a_renamed = dir.path() / "ground.h5";
  fs::rename(l2a, l2a_renamed);
  const CommandOutcome out = run_glaswave("retrieve " + l2a_renamed.string() + " " + l1b.string() +
                                          " --quiet --out " + (dir.path() / "out").string());
  ASSERT_EQ(out.status, 0) << out.output;
  const fs::path granule = dir.path() / "out" / "gedi_l2b.h5";
  for (const char* g : {"BEAM0000/", "BEAM0101/"}) {
    const std::string beam = g;
    const std::vector<double> cover = h5_dataset(granule, beam + "cover");
    const std::vector<double> pai = h5_dataset(granule, beam + "pai");
    ASSERT_FALSE(cover.empty()) << beam;
    for (std::size_t i = 0; i < cover.size(); ++i) {
      // Through L2A's thresholds the signal's end cuts the ground 3.8 sigma out: 1e-4 of it.
      EXPECT_NEAR(cover[i], 0.5, 0.01) << beam << i;
      EXPECT_NEAR(pai[i], -2.0 * std::log(0.5), 0.04) << beam << i;
      EXPECT_NEAR(h5_dataset(granule, beam + "geolocation/elev_lowestmode")[i], kGroundElevation,
                  0.05)
          << beam << i;
      EXPECT_NEAR(h5_dataset(granule, beam + "rhov")[i], 0.6, 1e-7);
    }
  }
  // BEAM0101's shots took the L2A's sensitivity, group and quality (the second's 0); BEAM0000's,
  // without an L2A, carry fill.
  EXPECT_NEAR(h5_dataset(granule, "BEAM0101/sensitivity")[0], 0.93, 1e-6);
  EXPECT_EQ(h5_dataset(granule, "BEAM0101/selected_l2a_algorithm")[0], 1.0);
  EXPECT_EQ(h5_dataset(granule, "BEAM0101/l2a_quality_flag"), (std::vector<double>{1.0, 0.0}));
  EXPECT_EQ(h5_dataset(granule, "BEAM0101/l2b_quality_flag"), (std::vector<double>{1.0, 0.0}));
  EXPECT_EQ(h5_dataset(granule, "BEAM0000/sensitivity")[0], -9999.0);
  EXPECT_EQ(h5_dataset(granule, "BEAM0101/channel")[0], 2.0);
  EXPECT_EQ(h5_dataset(granule, "BEAM0101/rh100")[0], 2500.0);  // the L2A's highest return
  // retrieval.nc: the same cover; no truth for a real granule.
  const fs::path nc = dir.path() / "out" / "retrieval.nc";
  const std::vector<double> cover_nc = nc_variable(nc, "cover_gedi_l2b");
  ASSERT_EQ(cover_nc.size(), 3u);
  for (double c : cover_nc) EXPECT_NEAR(c, 0.5, 0.01);
  EXPECT_TRUE(nc_variable(nc, "cover_true").empty());
  // rt compares watts with its table's: a real granule does not say its digitiser's counts per
  // watt, so rt asks for them before it reads a table; a scale that is no positive number is
  // refused too.
  const std::string rt = "retrieve " + l1b.string() + " --methods rt --table " +
                         (dir.path() / "table.nc").string() + " --quiet --out " +
                         (dir.path() / "rt").string();
  for (const std::string& line :
       {rt, rt + " --counts-per-watt 0", rt + " --counts-per-watt 1e9x"}) {
    const CommandOutcome refused = run_glaswave(line);
    EXPECT_EQ(refused.status, 2) << refused.output;
    EXPECT_NE(refused.output.find("--counts-per-watt"), std::string::npos) << refused.output;
    EXPECT_EQ(std::count(refused.output.begin(), refused.output.end(), '\n'), 1) << refused.output;
  }
  EXPECT_FALSE(fs::exists(dir.path() / "rt" / "retrieval.nc"));
}

// Each defect refused with status 3, one line naming the file and the dataset, nothing written.
TEST(RetrieveGedi, MalformedGranulesAreRefusedInOneLine) {
  const ScratchDir dir("glaswave_retrieve_gedi_malformed");
  struct Case {
    const char* name;
    L1bFile spec;
    const char* dataset;
  };
  L1bFile past, short_noise, no_bin0;
  past.start_past_end = true;
  short_noise.short_noise = true;
  no_bin0.skip_elevation_bin0 = true;
  const std::vector<Case> cases = {
      {"past.h5", past, "BEAM0101/rx_sample_start_index"},
      {"short_noise.h5", short_noise, "BEAM0000/noise_mean_corrected"},
      {"no_bin0.h5", no_bin0, "BEAM0000/geolocation/elevation_bin0"},
  };
  for (const Case& c : cases) {
    const fs::path file = dir.path() / c.name;
    write_l1b(file, c.spec);
    const fs::path out = dir.path() / (std::string(c.name) + ".out");
    const CommandOutcome refused =
        run_glaswave("retrieve " + file.string() + " --quiet --out " + out.string());
    EXPECT_EQ(refused.status, 3) << refused.output;
    EXPECT_NE(refused.output.find(file.string()), std::string::npos) << refused.output;
    EXPECT_NE(refused.output.find(c.dataset), std::string::npos) << refused.output;
    EXPECT_EQ(std::count(refused.output.begin(), refused.output.end(), '\n'), 1) << refused.output;
    EXPECT_FALSE(fs::exists(out / "retrieval.nc")) << c.name;
  }
  // rxwaveform declaring 10^12 samples, chunked and never written (a file of a few kB).
  const fs::path file = dir.path() / "huge.h5";
  write_l1b(file, {});
  {
    std::lock_guard lock(netcdf_library_mutex());
    const hid_t h = H5Fopen(file.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    ASSERT_GE(h, 0);
    H5Ldelete(h, "BEAM0000/rxwaveform", H5P_DEFAULT);
    const hsize_t dims[1] = {1000000000000ULL}, chunk[1] = {4096};
    const hid_t space = H5Screate_simple(1, dims, nullptr);
    const hid_t plist = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_chunk(plist, 1, chunk);
    const hid_t set = H5Dcreate2(h, "BEAM0000/rxwaveform", H5T_IEEE_F32LE, space, H5P_DEFAULT,
                                 plist, H5P_DEFAULT);
    ASSERT_GE(set, 0);
    H5Dclose(set);
    H5Pclose(plist);
    H5Sclose(space);
    H5Fclose(h);
  }
  ASSERT_LT(fs::file_size(file), 1000000u);
  const CommandOutcome refused = run_glaswave("retrieve " + file.string() + " --quiet --out " +
                                              (dir.path() / "huge").string());
  EXPECT_EQ(refused.status, 3) << refused.output;
  EXPECT_NE(refused.output.find("BEAM0000/rxwaveform"), std::string::npos) << refused.output;
  EXPECT_NE(refused.output.find("more than a file of"), std::string::npos) << refused.output;
  EXPECT_EQ(std::count(refused.output.begin(), refused.output.end(), '\n'), 1) << refused.output;
  // An L2A granule alone.
  const fs::path l2a = dir.path() / "l2a.h5";
  write_l2a(l2a);
  const CommandOutcome alone = run_glaswave("retrieve " + l2a.string() + " --quiet --out " +
                                            (dir.path() / "alone").string());
  EXPECT_EQ(alone.status, 3) << alone.output;
  EXPECT_NE(alone.output.find(l2a.string()), std::string::npos) << alone.output;
  EXPECT_NE(alone.output.find("give the L1B too"), std::string::npos) << alone.output;
  EXPECT_EQ(std::count(alone.output.begin(), alone.output.end(), '\n'), 1) << alone.output;
}

}  // namespace
}  // namespace glaswave
