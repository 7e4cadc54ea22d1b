// rt on ICESat-2's photons: Poisson's posterior over a hand-made table against the one computed
// here; glaswave's own ATL03 beside its ATL08 over a turbid layer (PHYSICS.md section 3) giving
// the layer's gap probability e^(-PAI/2), its PAI and its ground; and the refusals in one line.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "pipeline/retrieval/forward_table.hpp"
#include "pipeline/retrieval/rt_inversion.hpp"
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

// ATLAS's pulse and bins with a waveform receiver over turbid layers 5-15 m of PAI 0 to 5 (soil
// 0.3), the table; a pass of 300 shots (210 m, three ATL08 segments) over the layer of PAI 2.6 on
// a plane at 100 m, the sun's background at noon.
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
    nlohmann::json pass = test_support::atlas_pass(300, 1000, 7);
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
  // Twice the granule's own scale (1.81e17 a joule) expects twice the photons: the two whole
  // segments (100 m; the third holds 10 m of shots) are flagged misfits, where the granule's own
  // scale leaves their deviance near its expectation.
  const CommandOutcome doubled = run_glaswave(
      "retrieve " + granules() + " --photons-per-joule 3.6e17" + table + at("r5").string());
  ASSERT_EQ(doubled.status, 0) << doubled.output;
  const std::vector<double> flag = nc_variable(at("r5/retrieval.nc"), "rt_flag"),
                            ratio = nc_variable(at("r5/retrieval.nc"), "rt_chi2_per_dof");
  ASSERT_EQ(flag.size(), 3u);
  for (std::size_t i = 0; i < 2; ++i)
    EXPECT_NE(static_cast<int>(flag[i]) & rt_misfit, 0) << i << ": " << ratio[i];
}

}  // namespace
}  // namespace glaswave
