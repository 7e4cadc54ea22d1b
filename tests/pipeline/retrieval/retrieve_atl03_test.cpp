// rt on ICESat-2's photons: Poisson's posterior over a hand-made table against the one computed
// here; glaswave's own ATL03 beside its ATL08 over a turbid layer (PHYSICS.md section 3) giving
// the layer's gap probability e^(-PAI/2), its PAI and its ground; and the refusals in one line.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>

#include "core/hdf5_file.hpp"
#include "core/netcdf_lock.hpp"
#include "pipeline/config/config.hpp"
#include "pipeline/engine/inputs.hpp"
#include "pipeline/retrieval/forward_table.hpp"
#include "pipeline/retrieval/retrieve_inputs.hpp"
#include "pipeline/retrieval/rt_inversion.hpp"
#include "pipeline/transport/photon_counting.hpp"
#include "tests/pipeline/atlas_pass.hpp"
#include "tests/pipeline/engine/engine_test_support.hpp"
#include "tests/pipeline/retrieval/layer_table.hpp"
#include "tests/pipeline/retrieval/one_segment_atl08.hpp"
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

constexpr double kBinM = 0.1498962290;  // c 1 ns / 2

// Four entries whose whole return lies in the ground's bin, A_e W (1 ns bins, five bins from
// +0.3 m to -0.3 m), their PAIs 1 to 4.
ForwardTable ground_bin_table(const std::vector<double>& amplitude_W) {
  ForwardTable t;
  t.parameters = {{"canopy.pai", 0.0, 5.0, {}}};
  t.band_names = {"532"};
  t.bin_ns = 1.0;
  t.pulse_sigma_ns = 0.637;
  t.height_m = {2 * kBinM, kBinM, 0.0, -kBinM, -2 * kBinM};
  for (std::size_t e = 0; e < amplitude_W.size(); ++e) {
    t.parameter_values.push_back({1.0 + e});
    t.waveform_W.push_back({{0.0, 0.0, amplitude_W[e], 0.0, 0.0}});
    t.mc_sd_W.push_back({0.0});
    t.pai_true.push_back(1.0 + e);
    t.cover_true.push_back(0.2 * (1 + e));
    t.canopy_height_true_m.push_back(10.0);
    t.rhov_rhog.push_back(1.0);
  }
  t.shots_per_entry = 1;
  return t;
}

// N pulses, q photons a joule and 1 ns bins make entry e expect S_e = N q 1e-9 A_e photons in
// the ground's bin, and a background rate r adds B = N r 2 (0.15 m) / c to every bin. k photons
// at the ground: the posterior over entries is Poisson's, w_e ~ (S_e + B)^k e^(-S_e), at the
// ground's own shift (every other places the photons where the entry expects background alone,
// k ln(1 + S_e / B) = 75 lower).
TEST(RtPhotons, PosteriorIsPoissonsOverTheEntries) {
  const double pulses = 100.0, per_J = 1e17, rate_Hz = 1e5;  // B = 0.01, above the floor
  const std::vector<double> expected = {5.0, 10.0, 15.0, 20.0};
  std::vector<double> amplitude;
  for (double s : expected) amplitude.push_back(s / (pulses * per_J * 1e-9));
  const ForwardTable table = ground_bin_table(amplitude);
  RtSettings settings;
  settings.likelihood = RtLikelihood::constant_sd;  // the table's own waveforms, no emulator
  const RtInversion rt(table, settings);
  const std::vector<double> photons(12, 100.0);
  const RtResult r = rt.invert_photons({photons, pulses, rate_Hz, per_J, 100.0});
  const double background = pulses * rate_Hz * 2.0 * kBinM / 299792458.0;
  double total = 0.0, mean = 0.0, mean2 = 0.0;
  for (std::size_t e = 0; e < expected.size(); ++e) {
    const double w = std::exp(12.0 * std::log(expected[e] + background) - expected[e]);
    total += w;
    mean += w * (1.0 + e);
    mean2 += w * (1.0 + e) * (1.0 + e);
  }
  mean /= total;
  EXPECT_NEAR(r.pai.mean, mean, 1e-9);
  EXPECT_NEAR(r.pai.sd, std::sqrt(mean2 / total - mean * mean), 1e-9);
  EXPECT_NEAR(r.ground_elevation_m.mean, 100.0, 1e-9);
  EXPECT_EQ(r.best_entry, 1);  // 12 photons: S = 10 is likeliest
  EXPECT_EQ(r.flag, 0);
  // No photons per joule, no pulses: not run.
  EXPECT_EQ(rt.invert_photons({photons, pulses, rate_Hz, 0.0, 100.0}).flag, rt_not_run);
  EXPECT_EQ(rt.invert_photons({photons, 0.0, rate_Hz, per_J, 100.0}).flag, rt_not_run);
}

// A real-layout ATL03 (the data dictionary's names and dtypes) beside its ATL08, gt1l: 20 m
// segments 101-106 at segment_dist_x = 20 id, 2.857 ms apart (28.57 pulses), holding photons
// 2, 2, 2, 0, 2 and 1 (ph_index_beg 1-based, 0 for the empty one); ATL08's one land segment
// 101-105 on a terrain slope of 0.1; three background estimates, two inside the segment's time.
void write_real_layout(const fs::path& atl03, const fs::path& atl08) {
  std::lock_guard lock(netcdf_library_mutex());
  {
    Hdf5Writer f(atl03);
    f.write("gt1l/heights/h_ph", std::vector<float>{250.0f, 262.5f, 251.0f, 263.0f, 249.5f, 258.0f,
                                                    252.0f, 400.0f, 251.0f});
    f.write("gt1l/heights/dist_ph_along",
            std::vector<float>{1.0f, 5.0f, 2.0f, 18.0f, 0.5f, 10.0f, 19.5f, 7.0f, 3.0f});
    std::vector<double> photon_time(9);
    for (int i = 0; i < 9; ++i) photon_time[i] = 1000.0 + 0.0014 * i;
    f.write("gt1l/heights/delta_time", photon_time);
    f.write("gt1l/geolocation/segment_id", std::vector<std::int32_t>{101, 102, 103, 104, 105, 106});
    f.write("gt1l/geolocation/segment_dist_x",
            std::vector<double>{2020.0, 2040.0, 2060.0, 2080.0, 2100.0, 2120.0});
    f.write("gt1l/geolocation/ph_index_beg", std::vector<std::int64_t>{1, 3, 5, 0, 7, 9});
    f.write("gt1l/geolocation/segment_ph_cnt", std::vector<std::int32_t>{2, 2, 2, 0, 2, 1});
    std::vector<double> segment_time(6);
    for (int k = 0; k < 6; ++k) segment_time[k] = 1000.0 + k * 0.002857;
    f.write("gt1l/geolocation/delta_time", segment_time);
    f.write("gt1l/bckgrd_atlas/bckgrd_rate", std::vector<float>{1e6f, 2e6f, 3e6f});
    f.write("gt1l/bckgrd_atlas/delta_time", std::vector<double>{1000.0, 1000.005, 1000.02});
    f.close();
  }
  test_support::write_one_segment_atl08(atl08);
}

// The segment gets segments 101-105's eight photons (106's left out), each at x = segment_dist_x
// + dist_ph_along, its height less 0.1 (x - the middle of their span, 2021-2119.5 m: 2070.25 m);
// 143 pulses (5 x 2.857 ms at 10 kHz: 142.85); the background the mean of the estimates at
// 1000.0 and 1000.005 s (1.5 MHz); no photons per joule (a real granule), so that rt is refused
// until --photons-per-joule gives it.
TEST(RetrieveAtl03, RealLayoutGivesEachSegmentItsPhotons) {
  const ScratchDir dir("glaswave_retrieve_atl03_real");
  const fs::path atl03 = dir.path() / "ATL03_real.h5", atl08 = dir.path() / "ATL08_real.h5";
  write_real_layout(atl03, atl08);
  const MeasuredShots shots = read_retrieve_inputs({atl08, atl03}, std::nullopt, std::nullopt);
  ASSERT_EQ(shots.shots.size(), 1u);
  ASSERT_TRUE(shots.shots[0].photons.has_value());
  const PhotonSegment& p = *shots.shots[0].photons;
  const std::vector<double> h = {250.0, 262.5, 251.0, 263.0, 249.5, 258.0, 252.0, 400.0};
  const std::vector<double> x = {2021.0, 2025.0, 2042.0, 2058.0, 2060.5, 2070.0, 2119.5, 2107.0};
  ASSERT_EQ(p.heights_m.size(), h.size());
  for (std::size_t i = 0; i < h.size(); ++i)
    EXPECT_NEAR(p.heights_m[i], h[i] - 0.1 * (x[i] - 2070.25), 1e-4) << i;
  EXPECT_EQ(p.pulses, 143.0);
  EXPECT_NEAR(p.background_rate_Hz, 1.5e6, 1e-3);
  EXPECT_TRUE(std::isnan(p.photons_per_J));
  const CommandOutcome r = run_glaswave("retrieve " + atl03.string() + " " + atl08.string() +
                                        " --table " + (dir.path() / "none.nc").string() +
                                        " --quiet --out " + (dir.path() / "out").string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("--photons-per-joule"), std::string::npos) << r.output;
  EXPECT_EQ(lines(r.output), 1u) << r.output;
  EXPECT_FALSE(fs::exists(dir.path() / "out" / "retrieval.nc"));
}

// ATLAS's sensor over a turbid layer 5-15 m (spherical leaves, soil 0.3) on a plane: the table's
// configuration (a waveform receiver, two shots an entry, PAI over [0, 5], 64 entries).
nlohmann::json atlas_layer_table() {
  nlohmann::json table = test_support::layer_table_configuration(
      {{"preset", "atlas"}, {"receiver", "waveform"}}, 496000.0, 1000, 64);
  table["simulation"]["background"] = "none";
  return table;
}

// The photons of `shots` ATLAS shots (its photon-counting receiver, no background) over a layer
// of PAI `pai` on a plane 100 m up, another seed and place: one segment's heights.
std::vector<double> layer_photons(double pai, int shots, std::uint64_t seed) {
  nlohmann::json document = atlas_layer_table();
  document.erase("table");
  document["sensor"].erase("receiver");
  document["seed"] = seed;
  document["canopy"]["pai"] = pai;
  document["terrain"]["plane"]["elevation_m"] = 100.0;
  nlohmann::json points = nlohmann::json::array();
  for (int i = 0; i < shots; ++i)
    points.push_back({{"lat_deg", 0.01 + 1e-5 * i}, {"lon_deg", 0.0}});
  document["track"]["points"] = points;
  const Config config = parse_config(document);
  const auto terrain = open_terrain(config);
  const auto track = plan_track(config, *terrain);
  const auto simulator = make_shot_simulator(config, *terrain);
  std::vector<double> heights;
  for (int i = 0; i < shots; ++i) {
    const ShotRecord r = simulator->simulate(track->footprint(i));
    heights.insert(heights.end(), r.photon_h_m.begin(), r.photon_h_m.end());
  }
  return heights;
}

// The calibrated photon posterior (a second check of calibrate_photons, on forests the table
// did not see): 60 held-out layers, PAI along the golden-ratio sequence over [0, 5], each a
// segment of 40 shots (about 150 photons), against the 64-entry table. The 90 % interval should
// hold the truth in 54 of 60 (binomial sd 2.3): at least 45 and at most 59, as the waveforms'
// test asks, the mean posterior sd below 0.4 (the prior's 1.44) and the PAI's RMSE below 0.3.
TEST(RtPhotons, NinetyPercentIntervalsHoldHeldOutLayers) {
  const ForwardTable table = build_table({atlas_layer_table(), ".", 2}, {});
  RtInversion rt(table, RtSettings{});
  const double per_J = 0.45 * 0.15 / photon_energy_J(532.0), pulses = 40.0;
  rt.calibrate_photons(pulses, per_J, 0.0);
  int covered = 0;
  double sd = 0.0, squared = 0.0;
  for (int i = 0; i < 60; ++i) {
    const double pai = 5.0 * std::fmod(0.6180339887498949 * (i + 1), 1.0);
    const std::vector<double> photons = layer_photons(pai, 40, 7000 + i);
    const RtResult r = rt.invert_photons({photons, pulses, 0.0, per_J, 100.0});
    covered += r.pai.p05 <= pai && pai <= r.pai.p95;
    sd += r.pai.sd;
    squared += std::pow(r.pai.mean - pai, 2);
  }
  RecordProperty("pai_90_interval_covered", covered);
  RecordProperty("photon_tempering", std::to_string(rt.photon_tempering()));
  EXPECT_GE(covered, 45) << "tau " << rt.photon_tempering();
  EXPECT_LE(covered, 59);
  EXPECT_LT(sd / 60.0, 0.4);
  EXPECT_LT(std::sqrt(squared / 60.0), 0.3);
}

// ATLAS's pulse and bins with a waveform receiver over turbid layers 5-15 m of PAI 0 to 5 (soil
// 0.3), the table; a pass of 429 shots (300.3 m, three whole ATL08 segments) over the layer of
// PAI 2.6 on a plane at 100 m, the sun's background at noon.
nlohmann::json layer_canopy(double pai) {
  return {{"crown_shape", "layer"},
          {"crown_base_m", {5.0, 5.0}},
          {"crown_half_height_m", 5.0},
          {"dbh_m", 0.0},
          {"pai", pai},
          {"cover", 1.0}};
}

class Atl03Layer : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new ScratchDir("glaswave_retrieve_atl03");
    nlohmann::json pass = test_support::atlas_pass(429, 1000, 7);
    pass["canopy"] = layer_canopy(2.6);
    pass["terrain"]["soil_reflectance"] = 0.3;
    std::ofstream(dir_->path() / "pass.json") << pass.dump(2);
    nlohmann::json table = test_support::atlas_pass(2, 1000, 1);
    table["sensor"]["receiver"] = "waveform";
    table["canopy"] = layer_canopy(2.0);
    table["terrain"]["soil_reflectance"] = 0.3;
    table["track"] = {
        {"type", "points"},
        {"altitude_m", 496000.0},
        {"points",
         {{{"lat_deg", 10.0}, {"lon_deg", 0.0}}, {{"lat_deg", 10.001}, {"lon_deg", 0.0}}}}};
    table["table"] = {{"vary", {{"canopy.pai", {0.0, 5.0}}}}, {"entries", 60}};
    std::ofstream(dir_->path() / "table.json") << table.dump(2);
    ok_ = run_glaswave("run " + (dir_->path() / "pass.json").string() + " --quiet --out " +
                       (dir_->path() / "pass").string())
                  .status == 0 &&
          run_glaswave("table " + (dir_->path() / "table.json").string() + " --quiet --out " +
                       (dir_->path() / "table.nc").string())
                  .status == 0;
  }
  static void TearDownTestSuite() { delete dir_; }
  static fs::path at(const std::string& name) { return dir_->path() / name; }
  static std::string granules() {
    return at("pass/atl03.h5").string() + " " + at("pass/atl08.h5").string();
  }
  static inline ScratchDir* dir_ = nullptr;
  static inline bool ok_ = false;
};

TEST_F(Atl03Layer, PhotonsGiveTheLayersGapProbabilityPaiAndGround) {
  ASSERT_TRUE(ok_);
  const fs::path out = at("out");
  const CommandOutcome r = run_glaswave("retrieve " + granules() + " --table " +
                                        at("table.nc").string() + " --quiet --out " + out.string());
  ASSERT_EQ(r.status, 0) << r.output;
  const fs::path nc = out / "retrieval.nc";
  const std::vector<double> pgap = nc_variable(nc, "pgap_rt"), pai = nc_variable(nc, "pai_rt"),
                            low = nc_variable(nc, "pai_rt_p05"),
                            high = nc_variable(nc, "pai_rt_p95"),
                            ground = nc_variable(nc, "ground_elevation_rt"),
                            flag = nc_variable(nc, "rt_flag");
  ASSERT_EQ(pgap.size(), 3u);
  for (std::size_t i = 0; i < pgap.size(); ++i) {
    // A turbid layer of spherical leaves seen at nadir: Pgap = e^(-PAI / 2).
    EXPECT_NEAR(pgap[i], std::exp(-1.3), 0.04) << i;
    EXPECT_NEAR(pai[i], 2.6, 0.4) << i;
    EXPECT_LE(low[i], 2.6) << i;
    EXPECT_GE(high[i], 2.6) << i;
    EXPECT_NEAR(ground[i], 100.0, 0.1) << i;  // a pulse sigma is 0.095 m
    EXPECT_EQ(flag[i], 0.0) << i;
    EXPECT_LT(nc_variable(nc, "rt_chi2_per_dof")[i], 2.0) << i;
  }
  // The photon ratio beside it, from ATL08's counts of the same photons.
  EXPECT_EQ(nc_variable(nc, "cover_photon_ratio").size(), 3u);
}

TEST_F(Atl03Layer, RefusalsAreOneLine) {
  ASSERT_TRUE(ok_);
  const std::string table = " --table " + at("table.nc").string() + " --quiet --out ";
  struct Case {
    std::string arguments, says;
  } cases[] = {
      {at("pass/atl03.h5").string() + table + at("r1").string(), "beside the ATL08"},
      {at("pass/atl08.h5").string() + " --methods rt" + table + at("r2").string(),
       "give the ATL03 granule beside the ATL08"},
      {granules() + " " + at("pass/atl03.h5").string() + table + at("r3").string(),
       "one ATL03 granule is read beside one ATL08"},
      {granules() + " --photons-per-joule 0" + table + at("r4").string(), "--photons-per-joule"},
  };
  for (const Case& c : cases) {
    const CommandOutcome r = run_glaswave("retrieve " + c.arguments);
    EXPECT_NE(r.status, 0) << c.arguments;
    EXPECT_NE(r.output.find(c.says), std::string::npos) << r.output;
    EXPECT_EQ(lines(r.output), 1u) << r.output;
  }
  // Twice the granule's own scale (1.81e17 a joule) expects twice the photons: every segment is
  // flagged a misfit, where the granule's own scale leaves their deviance near its expectation.
  const CommandOutcome doubled = run_glaswave(
      "retrieve " + granules() + " --photons-per-joule 3.6e17" + table + at("r5").string());
  ASSERT_EQ(doubled.status, 0) << doubled.output;
  const std::vector<double> flag = nc_variable(at("r5/retrieval.nc"), "rt_flag"),
                            ratio = nc_variable(at("r5/retrieval.nc"), "rt_chi2_per_dof");
  ASSERT_EQ(flag.size(), 3u);
  for (std::size_t i = 0; i < flag.size(); ++i)
    EXPECT_NE(static_cast<int>(flag[i]) & rt_misfit, 0) << i << ": " << ratio[i];
}

}  // namespace
}  // namespace glaswave
