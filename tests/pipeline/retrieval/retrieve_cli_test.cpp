// `glaswave table` then `glaswave retrieve` as a user runs them, retrieval.nc read back under
// PRODUCT.md section 11's names; refusals one line with the contract's exit status.
#include <gtest/gtest.h>
#include <netcdf.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "tests/pipeline/engine/engine_test_support.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

using nlohmann::json;
using test_support::CommandOutcome;
using test_support::run_glaswave;
using test_support::ScratchDir;
namespace fs = std::filesystem;

// GEDI over a plane, a turbid layer 5-15 m; few rays (a test, not a study).
json layer(double pai, double elevation_m, int points) {
  json track_points = json::array();
  for (int i = 0; i < points; ++i)
    track_points.push_back({{"lat_deg", 0.001 * i}, {"lon_deg", 0.0}});
  return {
      {"sensor", {{"preset", "gedi"}}},
      {"simulation", {{"rays_per_shot", 1000}}},
      {"terrain",
       {{"plane", {{"origin_lat_deg", 0.0}, {"origin_lon_deg", 0.0}, {"elevation_m", elevation_m}}},
        {"soil_reflectance", 0.3}}},
      {"canopy",
       {{"crown_shape", "layer"},
        {"crown_base_m", {5.0, 5.0}},
        {"crown_half_height_m", 5.0},
        {"dbh_m", 0.0},
        {"pai", pai},
        {"cover", 1.0}}},
      {"track", {{"type", "points"}, {"points", track_points}, {"altitude_m", 420000.0}}},
      {"output", {{"footprints", false}}},
  };
}

std::string write(const fs::path& file, const json& document) {
  std::ofstream(file) << document.dump(2);
  return file.string();
}

std::vector<double> read_variable(int nc, const char* name, std::size_t expected) {
  int var = -1;
  EXPECT_EQ(nc_inq_varid(nc, name, &var), NC_NOERR) << name;
  std::vector<double> values(expected, -1.0);
  if (var >= 0) {
    EXPECT_EQ(nc_get_var_double(nc, var, values.data()), NC_NOERR) << name;
  }
  return values;
}

class RetrieveCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = std::make_unique<ScratchDir>("glaswave_retrieve");
    json table = layer(2.0, 0.0, 2);
    table["table"] = {{"vary", {{"canopy.pai", {0.0, 5.0}}}}, {"entries", 24}};
    const CommandOutcome made =
        run_glaswave("table " + write(dir_->path() / "table.json", table) + " --out " +
                     (dir_->path() / "table.nc").string() + " --quiet --threads 2");
    ASSERT_EQ(made.status, 0) << made.output;
    table_output_ = made.output;
    json pass = layer(2.6, 40.0, 4);
    pass["output"]["gedi_l1b"] = true;
    const CommandOutcome run = run_glaswave("run " + write(dir_->path() / "pass.json", pass) +
                                            " --quiet --out " + (dir_->path() / "pass").string());
    ASSERT_EQ(run.status, 0) << run.output;
  }
  static void TearDownTestSuite() { dir_.reset(); }
  static std::unique_ptr<ScratchDir> dir_;
  static std::string table_output_;
};
std::unique_ptr<ScratchDir> RetrieveCli::dir_;
std::string RetrieveCli::table_output_;

// The table's file: its entries, its axis and the configuration it came from.
TEST_F(RetrieveCli, TableHoldsItsEntriesAndConfiguration) {
  EXPECT_NE(table_output_.find("24 entries"), std::string::npos) << table_output_;
  int nc = -1;
  ASSERT_EQ(nc_open((dir_->path() / "table.nc").c_str(), NC_NOWRITE, &nc), NC_NOERR);
  std::size_t length = 0;
  ASSERT_EQ(nc_inq_attlen(nc, NC_GLOBAL, "config", &length), NC_NOERR);
  std::string config(length, '\0');
  nc_get_att_text(nc, NC_GLOBAL, "config", config.data());
  EXPECT_EQ(json::parse(config)["table"]["entries"], 24);
  int dim = -1;
  ASSERT_EQ(nc_inq_dimid(nc, "entry", &dim), NC_NOERR);
  nc_inq_dimlen(nc, dim, &length);
  EXPECT_EQ(length, 24u);
  const std::vector<double> pai = read_variable(nc, "param_canopy_pai", 24);
  for (double p : pai) EXPECT_TRUE(p >= 0.0 && p <= 5.0) << p;
  nc_close(nc);
}

// The four methods on four shots of a layer of PAI 2.6 over a plane 40 m up.
TEST_F(RetrieveCli, RetrieveWritesEveryMethodBesideTheTruth) {
  const fs::path out = dir_->path() / "retrieval";
  const CommandOutcome retrieve = run_glaswave(
      "retrieve " + (dir_->path() / "pass" / "shots.nc").string() + " --table " +
      (dir_->path() / "table.nc").string() + " --out " + out.string() + " --threads 2 --json");
  ASSERT_EQ(retrieve.status, 0) << retrieve.output;
  const json summary = json::parse(retrieve.output);
  EXPECT_EQ(summary["shots"], 4);
  EXPECT_EQ(summary["methods"], json({"gedi_l2a", "gedi_l2b", "wi", "rt"}));
  int nc = -1;
  ASSERT_EQ(nc_open((out / "retrieval.nc").c_str(), NC_NOWRITE, &nc), NC_NOERR);
  for (const char* name : {"shot_number", "beam", "lat", "lon"}) read_variable(nc, name, 4);
  for (const char* method : {"gedi_l2a", "gedi_l2b", "wi", "rt"})
    for (const char* v : {"canopy_height", "cover", "pai", "ground_elevation", "rhov_rhog", "pgap"})
      read_variable(nc, (std::string(v) + "_" + method).c_str(), 4);
  for (const char* v : {"canopy_height", "cover", "pai", "ground_elevation", "rhov_rhog", "pgap"})
    for (const char* part : {"_rt_sd", "_rt_p05", "_rt_p95", "_true"})
      read_variable(nc, (std::string(v) + part).c_str(), 4);
  read_variable(nc, "rt_flag", 4);
  read_variable(nc, "pavd_z_gedi_l2b", 4 * 30);
  const std::vector<double> pai_true = read_variable(nc, "pai_true", 4);
  const std::vector<double> pai = read_variable(nc, "pai_rt", 4);
  const std::vector<double> p05 = read_variable(nc, "pai_rt_p05", 4);
  const std::vector<double> p95 = read_variable(nc, "pai_rt_p95", 4);
  const std::vector<double> ground = read_variable(nc, "ground_elevation_rt", 4);
  const std::vector<double> ground_true = read_variable(nc, "ground_elevation_true", 4);
  const std::vector<double> l2a_ground = read_variable(nc, "ground_elevation_gedi_l2a", 4);
  const std::vector<double> pgap_true = read_variable(nc, "pgap_true", 4);
  const std::vector<double> pgap = read_variable(nc, "pgap_rt", 4);
  const std::vector<double> l2b_pgap = read_variable(nc, "pgap_gedi_l2b", 4);
  const std::vector<double> l2b_cover = read_variable(nc, "cover_gedi_l2b", 4);
  const std::vector<double> wi_pgap = read_variable(nc, "pgap_wi", 4);
  const std::vector<double> wi_cover = read_variable(nc, "cover_wi", 4);
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(pai_true[i], 2.6, 0.05);
    EXPECT_NEAR(pai[i], pai_true[i], 0.6);  // 24 entries of 1000 rays
    EXPECT_LE(p05[i], pai[i] + 1e-3);       // a posterior on one entry: equal but for rounding
    EXPECT_GE(p95[i], pai[i] - 1e-3);
    EXPECT_NEAR(ground[i], ground_true[i], 0.3);
    // The layer's gap probability e^-PAI/2 (G = 1/2, to the leaf-angle table's 2e-4); rt's
    // within the PAI's 0.6 carried through its slope, 0.5 e^-(2.6 - 0.6)/2 0.6 = 0.11; L2B's and
    // WI's one less their covers.
    EXPECT_NEAR(pgap_true[i], std::exp(-0.5 * pai_true[i]), 1.5e-4);
    EXPECT_NEAR(pgap[i], pgap_true[i], 0.11);
    if (std::isfinite(l2b_cover[i])) {
      EXPECT_NEAR(l2b_pgap[i], 1.0 - l2b_cover[i], 1e-15);
    }
    if (std::isfinite(wi_cover[i])) {
      EXPECT_NEAR(wi_pgap[i], 1.0 - wi_cover[i], 1e-15);
    }
    // L2A's selected group may take the lone far-scattered rays 20 m below for the ground
    // (a5's 2 sigma on a noise-free waveform): not checked here.
    (void)l2a_ground;
  }
  nc_close(nc);
  // An existing product is not overwritten.
  const CommandOutcome again =
      run_glaswave("retrieve " + (dir_->path() / "pass" / "shots.nc").string() + " --quiet --out " +
                   out.string());
  EXPECT_EQ(again.status, 2) << again.output;
}

// --plots draws DIR/plots/ (the estimates against the truth, the shots over rt's best fits);
// where the best fit lies is in retrieval.nc: on these noise-free layers its ground is the true
// ground, and L2A's default group a1 (a 6 sigma back threshold on the 1 %
// floor) finds the true ground too (both within 0.3 m, two bins, as rt's posterior mean above),
// where the selected group may not.
TEST_F(RetrieveCli, PlotsAndTheBestFitAreWritten) {
  const fs::path out = dir_->path() / "plotted";
  const CommandOutcome retrieve = run_glaswave(
      "retrieve " + (dir_->path() / "pass" / "shots.nc").string() + " --table " +
      (dir_->path() / "table.nc").string() + " --out " + out.string() + " --threads 2 --plots");
  ASSERT_EQ(retrieve.status, 0) << retrieve.output;
  EXPECT_EQ(retrieve.output.find("warning"), std::string::npos) << retrieve.output;
  for (const char* png : {"retrieval_estimates.png", "retrieval_fits.png"})
    EXPECT_GT(fs::file_size(out / "plots" / png), 1000u) << png;
  int nc = -1;
  ASSERT_EQ(nc_open((out / "retrieval.nc").c_str(), NC_NOWRITE, &nc), NC_NOERR);
  const std::vector<double> entry = read_variable(nc, "rt_best_entry", 4);
  const std::vector<double> best_ground = read_variable(nc, "rt_best_ground_elevation", 4);
  const std::vector<double> a1_ground = read_variable(nc, "ground_elevation_gedi_l2a_a1", 4);
  const std::vector<double> a1_height = read_variable(nc, "canopy_height_gedi_l2a_a1", 4);
  const std::vector<double> ground_true = read_variable(nc, "ground_elevation_true", 4);
  for (int i = 0; i < 4; ++i) {
    EXPECT_GE(entry[i], 0.0);
    EXPECT_LT(entry[i], 24.0);
    EXPECT_NEAR(best_ground[i], ground_true[i], 0.3);
    EXPECT_NEAR(a1_ground[i], ground_true[i], 0.3);
    // RH98 of a layer 5-15 m: below its top, above its base.
    EXPECT_GT(a1_height[i], 5.0);
    EXPECT_LT(a1_height[i], 15.0 + 3.0);
  }
  nc_close(nc);
}

// rt on the pass's GEDI L1B granule: its counts put on the table's scale by the granule's own
// counts_per_watt give rt what shots.nc gives (float32 counts: to 1e-4), and the truth of the
// layer (PAI 2.6, its gap probability e^-1.3) comes back with them. Told a scale twice the
// granule's (--counts-per-watt), rt sees waveforms half as bright as any forest of its table
// and flags every shot.
TEST_F(RetrieveCli, RtReadsAGediGranuleOnItsDigitisersScale) {
  const std::string table = " --table " + (dir_->path() / "table.nc").string();
  const fs::path from_shots = dir_->path() / "l1b_shots", from_l1b = dir_->path() / "l1b_l1b",
                 halved = dir_->path() / "l1b_halved";
  ASSERT_EQ(run_glaswave("retrieve " + (dir_->path() / "pass" / "shots.nc").string() + table +
                         " --methods rt --quiet --out " + from_shots.string())
                .status,
            0);
  const std::string l1b = (dir_->path() / "pass" / "gedi_l1b.h5").string();
  const CommandOutcome retrieved =
      run_glaswave("retrieve " + l1b + table + " --methods rt --quiet --out " + from_l1b.string());
  ASSERT_EQ(retrieved.status, 0) << retrieved.output;
  const CommandOutcome told = run_glaswave("retrieve " + l1b + table +
                                           " --methods rt --counts-per-watt 2e9 --quiet --json "
                                           "--out " +
                                           halved.string());
  ASSERT_EQ(told.status, 0) << told.output;
  EXPECT_EQ(json::parse(told.output)["rt_flagged"], 4);
  int a = -1, b = -1;
  ASSERT_EQ(nc_open((from_shots / "retrieval.nc").c_str(), NC_NOWRITE, &a), NC_NOERR);
  ASSERT_EQ(nc_open((from_l1b / "retrieval.nc").c_str(), NC_NOWRITE, &b), NC_NOERR);
  for (const char* name : {"pai_rt", "pgap_rt", "ground_elevation_rt", "pai_rt_sd"}) {
    const std::vector<double> x = read_variable(a, name, 4), y = read_variable(b, name, 4);
    for (int i = 0; i < 4; ++i) EXPECT_NEAR(y[i], x[i], 1e-4) << name << " " << i;
  }
  const std::vector<double> pai = read_variable(b, "pai_rt", 4);
  const std::vector<double> pgap_true = read_variable(b, "pgap_true", 4);
  const std::vector<double> flags = read_variable(b, "rt_flag", 4);
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(pai[i], 2.6, 0.6);
    EXPECT_NEAR(pgap_true[i], std::exp(-0.5 * 2.6), 1.5e-4);  // float32 in the granule
    EXPECT_EQ(flags[i], 0.0);
  }
  nc_close(a);
  nc_close(b);
}

// --beams and --bbox keep the pass's shots (beam 5, BEAM0101; at latitudes 0, 0.001, 0.002 and
// 0.003 on the prime meridian) in the beams and the box; a box whose west lies east of its east
// crosses the antimeridian and so holds none of them. A beam no input holds, or a box that is no
// box, is refused in one line.
TEST_F(RetrieveCli, BeamsAndBoxSelectShots) {
  const std::string l1b = (dir_->path() / "pass" / "gedi_l1b.h5").string();
  const fs::path kept = dir_->path() / "kept", none = dir_->path() / "none";
  ASSERT_EQ(run_glaswave("retrieve " + l1b +
                         " --beams BEAM0101,5 --bbox -1,0.0015,1,1 --quiet "
                         "--out " +
                         kept.string())
                .status,
            0);
  int nc = -1;
  ASSERT_EQ(nc_open((kept / "retrieval.nc").c_str(), NC_NOWRITE, &nc), NC_NOERR);
  EXPECT_EQ(read_variable(nc, "shot_number", 2), (std::vector<double>{2, 3}));
  nc_close(nc);
  const CommandOutcome across =
      run_glaswave("retrieve " + l1b + " --bbox 1,-1,-1,1 --quiet --json --out " + none.string());
  ASSERT_EQ(across.status, 0) << across.output;
  EXPECT_EQ(json::parse(across.output)["shots"], 0);
  const CommandOutcome beam = run_glaswave("retrieve " + l1b + " --beams BEAM0000 --quiet --out " +
                                           (dir_->path() / "refused").string());
  EXPECT_EQ(beam.status, 2) << beam.output;
  EXPECT_NE(beam.output.find("BEAM0000 is in none of the inputs, whose shots are in BEAM0101"),
            std::string::npos)
      << beam.output;
  for (const char* box : {"1,2,3", "0,1,2,-1", "0,0,181,1", "0,0,1,x"}) {
    const CommandOutcome refused =
        run_glaswave("retrieve " + l1b + " --bbox " + box + " --quiet --out " +
                     (dir_->path() / "refused").string());
    EXPECT_EQ(refused.status, 2) << box << ": " << refused.output;
    EXPECT_NE(refused.output.find("--bbox"), std::string::npos) << refused.output;
    EXPECT_EQ(std::count(refused.output.begin(), refused.output.end(), '\n'), 1) << refused.output;
  }
  EXPECT_FALSE(fs::exists(dir_->path() / "refused" / "retrieval.nc"));
}

// GLAS: a table of layers and a pass with a detector, written as shots.nc and as GLAH01 and
// GLAH14. rt on the two granules (GLAH01 placed by its GLAH14: the last sample at d_elev +
// d_ldRngOff) finds the ground 40 m up and the layer's PAI 2.6 as on shots.nc; the granules'
// truth is the layer's. A GLAH01 without its GLAH14, or a GLAH14 alone, is refused in one line.
TEST(RetrieveGlas, Glah01BesideItsGlah14GivesWhatItsShotsGive) {
  const ScratchDir dir("glaswave_retrieve_glas");
  const auto glas = [](json config) {
    config["sensor"] = {{"preset", "glas"},
                        {"bands",
                         {{{"name", "1064"},
                           {"wavelength_nm", 1064},
                           {"pulse_energy_mJ", 72},
                           {"atmos_transmission_roundtrip", 0.9}}}}};
    config["track"]["altitude_m"] = 600000.0;
    return config;
  };
  json table = glas(layer(2.0, 0.0, 2));
  table["table"] = {{"vary", {{"canopy.pai", {0.0, 5.0}}}}, {"entries", 24}};
  const fs::path table_file = dir.path() / "table.nc";
  ASSERT_EQ(run_glaswave("table " + write(dir.path() / "table.json", table) + " --quiet --out " +
                         table_file.string())
                .status,
            0);
  json pass = glas(layer(2.6, 40.0, 4));
  pass["detector"] = {{"enabled", true}, {"background_W", 2e-9}, {"noise_rms_W", 2e-9}};
  pass["output"]["glah01"] = pass["output"]["glah14"] = true;
  ASSERT_EQ(run_glaswave("run " + write(dir.path() / "pass.json", pass) + " --quiet --out " +
                         (dir.path() / "pass").string())
                .status,
            0);
  const std::string glah01 = (dir.path() / "pass" / "glah01.h5").string();
  const std::string glah14 = (dir.path() / "pass" / "glah14.h5").string();
  const std::string rt = " --methods rt --table " + table_file.string() + " --quiet --out ";
  ASSERT_EQ(run_glaswave("retrieve " + (dir.path() / "pass" / "shots.nc").string() + rt +
                         (dir.path() / "a").string())
                .status,
            0);
  // The GLAH14 first: the kind from the layout, not the order.
  const CommandOutcome granules =
      run_glaswave("retrieve " + glah14 + " " + glah01 + rt + (dir.path() / "b").string());
  ASSERT_EQ(granules.status, 0) << granules.output;
  int a = -1, b = -1;
  ASSERT_EQ(nc_open((dir.path() / "a" / "retrieval.nc").c_str(), NC_NOWRITE, &a), NC_NOERR);
  ASSERT_EQ(nc_open((dir.path() / "b" / "retrieval.nc").c_str(), NC_NOWRITE, &b), NC_NOERR);
  EXPECT_EQ(read_variable(b, "shot_number", 4), read_variable(a, "shot_number", 4));
  // The granule's noise is taken before the signal, shots.nc's at the window's quieter end.
  for (const char* name : {"pai_rt", "ground_elevation_rt", "lat", "lon"}) {
    const std::vector<double> x = read_variable(a, name, 4), y = read_variable(b, name, 4);
    for (int i = 0; i < 4; ++i) EXPECT_NEAR(y[i], x[i], 0.02) << name << " " << i;
  }
  // GLAH14's d_DEM_elv is shots.nc's terrain under the footprint.
  const std::vector<double> terrain = read_variable(a, "ground_elevation_true", 4);
  const std::vector<double> pai = read_variable(b, "pai_rt", 4);
  const std::vector<double> ground = read_variable(b, "ground_elevation_rt", 4);
  const std::vector<double> ground_true = read_variable(b, "ground_elevation_true", 4);
  const std::vector<double> pai_true = read_variable(b, "pai_true", 4);
  const std::vector<double> pgap_true = read_variable(b, "pgap_true", 4);
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(pai[i], 2.6, 0.6);
    EXPECT_NEAR(ground[i], 40.0, 0.3);
    EXPECT_NEAR(ground_true[i], terrain[i], 1e-6);
    EXPECT_NEAR(ground_true[i], 40.0, 1e-3);
    EXPECT_NEAR(pai_true[i], 2.6, 0.05);
    EXPECT_NEAR(pgap_true[i], std::exp(-0.5 * pai_true[i]), 1.5e-4);
  }
  nc_close(a);
  nc_close(b);
  const CommandOutcome alone =
      run_glaswave("retrieve " + glah01 + " --quiet --out " + (dir.path() / "c").string());
  EXPECT_EQ(alone.status, 3) << alone.output;
  EXPECT_NE(alone.output.find("GLAH14"), std::string::npos) << alone.output;
  const CommandOutcome placed_only =
      run_glaswave("retrieve " + glah14 + " --quiet --out " + (dir.path() / "c").string());
  EXPECT_EQ(placed_only.status, 3) << placed_only.output;
  EXPECT_NE(placed_only.output.find("GLAH01"), std::string::npos) << placed_only.output;
  for (const CommandOutcome* refused : {&alone, &placed_only})
    EXPECT_EQ(std::count(refused->output.begin(), refused->output.end(), '\n'), 1)
        << refused->output;
  EXPECT_FALSE(fs::exists(dir.path() / "c" / "retrieval.nc"));
}

// A table of other bins or another pulse, a missing input, rt without a table: one line, status
// 3, 3, 3 and 2, and no retrieval.nc (nor its .part).
TEST_F(RetrieveCli, RefusalsAreOneLine) {
  json other = layer(2.0, 0.0, 1);
  other["sensor"]["bin_ns"] = 2.0;
  other["table"] = {{"vary", {{"canopy.pai", {0.0, 5.0}}}}, {"entries", 2}, {"shots_per_entry", 1}};
  // In a folder not there yet: `table` makes it, as `run` makes its own (it said "Permission
  // denied" after simulating the whole table before).
  const fs::path other_table = dir_->path() / "new" / "folder" / "other.nc";
  ASSERT_EQ(run_glaswave("table " + write(dir_->path() / "other.json", other) + " --quiet --out " +
                         other_table.string())
                .status,
            0);
  const fs::path out = dir_->path() / "refused";
  const std::string shots = (dir_->path() / "pass" / "shots.nc").string();
  const CommandOutcome bins = run_glaswave("retrieve " + shots + " --quiet --table " +
                                           other_table.string() + " --out " + out.string());
  EXPECT_EQ(bins.status, 3) << bins.output;
  EXPECT_NE(bins.output.find("bins of 2"), std::string::npos) << bins.output;
  EXPECT_NE(bins.output.find(other_table.string()), std::string::npos) << bins.output;
  // Another sensor's pulse (GLAS's 5 ns for GEDI's 6.625): refused, not fitted badly.
  json pulse = layer(2.0, 0.0, 1);
  pulse["sensor"]["pulse_sigma_ns"] = 5.0;
  pulse["table"] = other["table"];
  const fs::path pulse_table = dir_->path() / "pulse.nc";
  ASSERT_EQ(run_glaswave("table " + write(dir_->path() / "pulse.json", pulse) + " --quiet --out " +
                         pulse_table.string())
                .status,
            0);
  const CommandOutcome pulses = run_glaswave("retrieve " + shots + " --quiet --table " +
                                             pulse_table.string() + " --out " + out.string());
  EXPECT_EQ(pulses.status, 3) << pulses.output;
  EXPECT_NE(pulses.output.find("pulse sigma of 5"), std::string::npos) << pulses.output;
  const CommandOutcome missing = run_glaswave("retrieve " + (dir_->path() / "nothere.nc").string() +
                                              " --quiet --out " + out.string());
  EXPECT_EQ(missing.status, 3) << missing.output;
  EXPECT_NE(missing.output.find("nothere.nc"), std::string::npos) << missing.output;
  const CommandOutcome no_table =
      run_glaswave("retrieve " + shots + " --methods rt --quiet --out " + out.string());
  EXPECT_EQ(no_table.status, 2) << no_table.output;
  // rt's search is one of three names.
  const CommandOutcome search =
      run_glaswave("retrieve " + shots + " --rt-search nearest --table " +
                   (dir_->path() / "table.nc").string() + " --quiet --out " + out.string());
  EXPECT_EQ(search.status, 2) << search.output;
  EXPECT_NE(search.output.find("--rt-search"), std::string::npos) << search.output;
  for (const CommandOutcome* refused : {&bins, &pulses, &missing, &no_table, &search}) {
    EXPECT_EQ(std::count(refused->output.begin(), refused->output.end(), '\n'), 1)
        << refused->output;
  }
  EXPECT_FALSE(fs::exists(out / "retrieval.nc"));
  EXPECT_FALSE(fs::exists(out / "retrieval.nc.part"));
}

}  // namespace
}  // namespace glaswave
