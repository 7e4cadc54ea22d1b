// `glaswave retrieve` on ICESat-2 ATL08 granules: a hand-made file in the real layout (the ATL08
// dictionary's names and dtypes) whose photon counts give the photon-ratio cover in closed form,
// glaswave's own atl08.h5 with its truth, and the refusals (a method of the other kind, a
// malformed granule, ATL08 mixed with waveforms) in one line.
#include <gtest/gtest.h>
#include <netcdf.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <mutex>
#include <nlohmann/json.hpp>

#include "core/hdf5_file.hpp"
#include "core/netcdf_lock.hpp"
#include "tests/pipeline/atlas_pass.hpp"
#include "tests/pipeline/engine/engine_test_support.hpp"
#include "tests/pipeline/retrieval/shot_variable.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

using test_support::CommandOutcome;
using test_support::run_glaswave;
using test_support::ScratchDir;
namespace fs = std::filesystem;

const auto& nc_variable = test_support::shot_variable;

std::size_t lines(const std::string& text) { return std::count(text.begin(), text.end(), '\n'); }

constexpr float kFill = std::numeric_limits<float>::max();  // ATL08's 3.4028235e38

// gt1l: segments 101 and 106 of 30 canopy, 10 top-of-canopy and 60 ground photons (cover 0.4,
// Pgap 0.6, PAI -2 ln 0.6 at nadir), h_canopy 17.5 m over a best-fit terrain of 250.25 m; gt3r:
// segment 101 of canopy photons alone (cover 1: no gap seen, no PAI) and segment 106 with no
// photons and fill for its heights.
void write_atl08(const fs::path& path, bool without_canopy_photons = false) {
  std::lock_guard lock(netcdf_library_mutex());
  Hdf5Writer f(path);
  for (const std::string beam : {"gt1l", "gt3r"}) {
    const std::string land = beam + "/land_segments/";
    const bool first = beam == "gt1l";
    f.write(land + "segment_id_beg", std::vector<std::int32_t>{101, 106});
    f.write(land + "latitude", std::vector<float>{10.0f, 10.001f});
    f.write(land + "longitude", std::vector<float>{20.0f, 20.0f});
    f.write(land + "canopy/h_canopy",
            first ? std::vector<float>{17.5f, 17.5f} : std::vector<float>{12.0f, kFill});
    f.write(land + "terrain/h_te_best_fit",
            first ? std::vector<float>{250.25f, 250.25f} : std::vector<float>{kFill, kFill});
    if (!without_canopy_photons)
      f.write(land + "canopy/n_ca_photons",
              first ? std::vector<std::int32_t>{30, 30} : std::vector<std::int32_t>{5, 0});
    f.write(land + "canopy/n_toc_photons",
            first ? std::vector<std::int32_t>{10, 10} : std::vector<std::int32_t>{2, 0});
    f.write(land + "terrain/n_te_photons",
            first ? std::vector<std::int32_t>{60, 60} : std::vector<std::int32_t>{0, 0});
  }
  f.close();
}

TEST(RetrieveAtl08, RealLayoutGivesThePhotonRatioInClosedForm) {
  const ScratchDir dir("glaswave_retrieve_atl08_real");
  const fs::path atl08 = dir.path() / "ATL08_20190320_minimal.h5";
  write_atl08(atl08);
  const fs::path out = dir.path() / "out";
  const CommandOutcome retrieved =
      run_glaswave("retrieve " + atl08.string() + " --quiet --json --out " + out.string());
  ASSERT_EQ(retrieved.status, 0) << retrieved.output;
  EXPECT_EQ(nlohmann::json::parse(retrieved.output)["methods"],
            nlohmann::json({"atl08", "photon_ratio"}));
  const fs::path nc = out / "retrieval.nc";
  EXPECT_EQ(nc_variable(nc, "shot_number"), (std::vector<double>{101, 106, 101, 106}));
  EXPECT_EQ(nc_variable(nc, "beam"), (std::vector<double>{1, 1, 6, 6}));
  const std::vector<double> cover = nc_variable(nc, "cover_photon_ratio");
  const std::vector<double> pgap = nc_variable(nc, "pgap_photon_ratio");
  const std::vector<double> pai = nc_variable(nc, "pai_photon_ratio");
  const std::vector<double> height = nc_variable(nc, "canopy_height_atl08");
  const std::vector<double> ground = nc_variable(nc, "ground_elevation_atl08");
  ASSERT_EQ(cover.size(), 4u);
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR(cover[i], 0.4, 1e-15);
    EXPECT_NEAR(pgap[i], 0.6, 1e-15);
    EXPECT_NEAR(pai[i], -2.0 * std::log(0.6), 1e-14);
    EXPECT_EQ(height[i], 17.5);
    EXPECT_EQ(ground[i], 250.25);
  }
  EXPECT_EQ(cover[2], 1.0);
  EXPECT_TRUE(std::isnan(pai[2]));
  EXPECT_TRUE(std::isnan(ground[2]));  // fill
  EXPECT_TRUE(std::isnan(cover[3]));   // no photons
  EXPECT_TRUE(std::isnan(height[3]));
  EXPECT_TRUE(nc_variable(nc, "cover_true").empty());  // no truth in a real granule
  // --shots selects by segment_id_beg, --beams by the track's number.
  ASSERT_EQ(
      run_glaswave("retrieve " + atl08.string() + " --shots 106:107 --beams 6 --quiet --out " +
                   (dir.path() / "one").string())
          .status,
      0);
  EXPECT_EQ(nc_variable(dir.path() / "one" / "retrieval.nc", "beam"), (std::vector<double>{6}));
}

// A waveform method on ATL08, ATL08's on waveforms, ATL08 beside a shots.nc, a dataset missing:
// one line each (status 2 for the methods, 3 for the files), nothing written.
TEST(RetrieveAtl08, RefusalsAreOneLine) {
  const ScratchDir dir("glaswave_retrieve_atl08_refused");
  const fs::path atl08 = dir.path() / "atl08.h5", broken = dir.path() / "broken.h5";
  write_atl08(atl08);
  write_atl08(broken, true);
  nlohmann::json pass = test_support::atlas_pass(150, 30, 4);
  pass["output"]["netcdf"] = true;
  std::ofstream(dir.path() / "pass.json") << pass.dump(2);
  ASSERT_EQ(run_glaswave("run " + (dir.path() / "pass.json").string() + " --quiet --out " +
                         (dir.path() / "pass").string())
                .status,
            0);
  const std::string shots = (dir.path() / "pass" / "shots.nc").string();
  const std::string out = " --quiet --out " + (dir.path() / "refused").string();
  struct Case {
    std::string line;
    int status;
    const char* says;
  };
  const std::vector<Case> cases = {
      {atl08.string() + " --methods gedi_l2b", 2, "choose among atl08, photon_ratio"},
      {shots + " --methods photon_ratio", 2, "choose among gedi_l2a"},
      {atl08.string() + " " + shots, 3, "retrieved apart"},
      {broken.string(), 3, "gt1l/land_segments/canopy/n_ca_photons: missing"},
  };
  for (const Case& c : cases) {
    const CommandOutcome refused = run_glaswave("retrieve " + c.line + out);
    EXPECT_EQ(refused.status, c.status) << c.line << ": " << refused.output;
    EXPECT_NE(refused.output.find(c.says), std::string::npos) << refused.output;
    EXPECT_EQ(lines(refused.output), 1u) << refused.output;
  }
  EXPECT_FALSE(fs::exists(dir.path() / "refused" / "retrieval.nc"));
}

// glaswave's own atl08.h5 over the seed's Table 1 forest on a plane at 100 m: ATL08's terrain
// within 0.1 m of it, and the truth carried through, where a crown forest's gap probability can
// be no less than the gaps between its crowns (Pgap >= 1 - crown cover).
TEST(RetrieveAtl08, GlaswavesOwnGranuleCarriesItsTruth) {
  const ScratchDir dir("glaswave_retrieve_atl08_own");
  nlohmann::json pass = test_support::atlas_pass(600, 300, 3);
  pass["output"]["atl08"] = true;
  std::ofstream(dir.path() / "pass.json") << pass.dump(2);
  ASSERT_EQ(run_glaswave("run " + (dir.path() / "pass.json").string() + " --quiet --out " +
                         (dir.path() / "pass").string())
                .status,
            0);
  const fs::path out = dir.path() / "out";
  ASSERT_EQ(run_glaswave("retrieve " + (dir.path() / "pass" / "atl08.h5").string() +
                         " --quiet --out " + out.string())
                .status,
            0);
  const fs::path nc = out / "retrieval.nc";
  const std::vector<double> ground = nc_variable(nc, "ground_elevation_atl08");
  const std::vector<double> ground_true = nc_variable(nc, "ground_elevation_true");
  const std::vector<double> pgap_true = nc_variable(nc, "pgap_true");
  const std::vector<double> cover_true = nc_variable(nc, "cover_true");
  const std::vector<double> cover = nc_variable(nc, "cover_photon_ratio");
  ASSERT_GE(ground.size(), 4u);
  for (std::size_t i = 0; i < ground.size(); ++i) {
    EXPECT_NEAR(ground_true[i], 100.0, 1e-3) << i;
    EXPECT_NEAR(ground[i], 100.0, 0.1) << i;
    EXPECT_GE(pgap_true[i], 1.0 - cover_true[i] - 1e-6) << i;
    EXPECT_LE(pgap_true[i], 1.0) << i;
    EXPECT_GT(cover[i], 0.0) << i;
    EXPECT_LT(cover[i], 1.0) << i;
  }
}

}  // namespace
}  // namespace glaswave
