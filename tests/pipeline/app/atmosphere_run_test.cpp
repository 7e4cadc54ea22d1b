// End to end: the `atmosphere` section in a run of the built command (issue 40). A GLAS pass over
// a level plane through `cirrus` against the same pass through `clear`: the cirrus's two-way
// extinction and the little it scatters forward into the field of view; and through `stratus`,
// whose forward-scattered light comes back late.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <netcdf.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tests/pipeline/engine/engine_test_support.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

namespace fs = std::filesystem;
using test_support::run_glaswave;

constexpr int shots = 3, bands = 2;

struct Returns {
  std::vector<double> energy_J;  // [shot][band]
  std::vector<double> mean_ns;   // [shot][band]: the waveform's energy-weighted mean time
  // [shot][band], the atmosphere's truth; empty where shots.nc has no such variable.
  std::vector<double> transmission, scattered, delay_m;
  std::string delay_units;
};

// A [shot][band] variable, or nothing where the file has none.
std::vector<double> read_optional(int nc, const char* name) {
  int var = -1;
  if (nc_inq_varid(nc, name, &var) != NC_NOERR) return {};
  std::vector<double> values(shots * bands);
  EXPECT_EQ(nc_get_var_double(nc, var, values.data()), NC_NOERR) << name;
  return values;
}

Returns read_returns(const fs::path& file) {
  Returns r;
  int nc = -1, var = -1;
  EXPECT_EQ(nc_open(file.c_str(), NC_NOWRITE, &nc), NC_NOERR) << file;
  r.energy_J.resize(shots * bands);
  EXPECT_EQ(nc_inq_varid(nc, "rx_energy", &var), NC_NOERR);
  EXPECT_EQ(nc_get_var_double(nc, var, r.energy_J.data()), NC_NOERR);
  int dims[3];
  std::size_t bins = 0;
  EXPECT_EQ(nc_inq_varid(nc, "rx_waveform", &var), NC_NOERR);
  EXPECT_EQ(nc_inq_vardimid(nc, var, dims), NC_NOERR);
  nc_inq_dimlen(nc, dims[2], &bins);
  std::vector<double> waveforms(shots * bands * bins);
  EXPECT_EQ(nc_get_var_double(nc, var, waveforms.data()), NC_NOERR);
  r.transmission = read_optional(nc, "atmosphere_transmission");
  r.scattered = read_optional(nc, "atmosphere_scattered_fraction");
  r.delay_m = read_optional(nc, "atmosphere_delay_m");
  if (nc_inq_varid(nc, "atmosphere_delay_m", &var) == NC_NOERR) {
    std::size_t length = 0;
    nc_inq_attlen(nc, var, "units", &length);
    r.delay_units.resize(length);
    nc_get_att_text(nc, var, "units", r.delay_units.data());
  }
  nc_close(nc);
  for (int k = 0; k < shots * bands; ++k) {
    double sum = 0.0, moment = 0.0;
    for (std::size_t bin = 0; bin < bins; ++bin) {
      sum += waveforms[k * bins + bin];
      moment += waveforms[k * bins + bin] * static_cast<double>(bin);  // 1 ns bins
    }
    r.mean_ns.push_back(moment / sum);
  }
  return r;
}

class AtmosphereRun : public ::testing::Test {
 protected:
  Returns run(const std::string& atmosphere) {
    nlohmann::json config = {
        {"seed", 3},
        {"sensor", {{"preset", "glas"}}},
        {"atmosphere", atmosphere},
        {"simulation", {{"rays_per_shot", 100000}}},
        {"terrain",
         {{"plane", {{"origin_lat_deg", 46.0}, {"origin_lon_deg", 8.0}, {"elevation_m", 900.0}}}}},
        {"canopy", nullptr},
        {"track",
         {{"type", "pass"},
          {"start_lat_deg", 46.0},
          {"start_lon_deg", 8.0},
          {"heading_deg", 350.0},
          {"shots", shots},
          {"spacing_m", 172.0}}},
        {"output", {{"footprints", false}}}};
    if (atmosphere == "none") config.erase("atmosphere");
    const fs::path file = dir_.path() / (atmosphere + ".json");
    std::ofstream(file) << config.dump(2);
    const auto out = dir_.path() / atmosphere;
    const auto outcome = run_glaswave("run " + file.string() + " --out " + out.string());
    EXPECT_EQ(outcome.status, 0) << outcome.output;
    return read_returns(out / "shots.nc");
  }

  test_support::ScratchDir dir_{"glaswave_atmosphere"};
};

// The part of a Henyey-Greenstein layer's scattering within angle theta of the forward
// direction: integral of (1 - g^2) / 2 (1 + g^2 - 2 g mu)^(-3/2) over mu from cos(theta) to 1.
double hg_forward_fraction(double g, double theta) {
  const double mu0 = std::cos(theta);
  return (1.0 - g * g) / (2.0 * g) *
         (1.0 / (1.0 - g) - 1.0 / std::sqrt(1.0 + g * g - 2.0 * g * mu0));
}

TEST_F(AtmosphereRun, CirrusDimsTheReturnByItsTwoWayTransmission) {
  const Returns clear = run("clear");
  const Returns cirrus = run("cirrus");
  // At nadir (mu = 1) the cirrus (tau 0.3, over clear's layers) passes exp(-2 tau) of the clear
  // return straight. What it scatters stays in view when it turns by less than the field of
  // view's radius (600 km x 0.2 mrad = 120 m) seen from the cloud (8.1-10.1 km above the plane
  // at 900 m): on each way at most tau times the HG(0.77) part within 120 m / 8100 m, 0.1 %
  // of the return here. Tolerance: 100 000 rays a shot leave 0.18 % of Monte Carlo noise in a
  // shot's direct part (binomial, 26 % of rays scattered), 0.1 % on the mean of 3 shots: 0.5 %.
  const double tau = 0.3, direct = std::exp(-2.0 * tau);
  const double forward = 2.0 * tau * hg_forward_fraction(0.77, 120.0 / 8100.0);
  EXPECT_LT(forward, 0.003);
  for (int band = 0; band < bands; ++band) {
    double ratio = 0.0, delay_ns = 0.0;
    for (int shot = 0; shot < shots; ++shot) {
      const int k = shot * bands + band;
      ratio += cirrus.energy_J[k] / clear.energy_J[k] / shots;
      delay_ns += (cirrus.mean_ns[k] - clear.mean_ns[k]) / shots;
    }
    EXPECT_GT(ratio, direct * (1.0 - 0.005)) << band;
    EXPECT_LT(ratio, direct * (1.0 + forward + 0.005)) << band;
    // Its forward-scattered light comes late, by at most R^2 / (2 H) = 0.9 m (3 ns) on each way;
    // a 0.1 % part of the return moves the mean time by picoseconds, far within the 0.03 ns of
    // noise the boundary layer's scattering leaves: the mean is the clear one's.
    EXPECT_NEAR(delay_ns, 0.0, 0.1) << band;
  }
  // Its truth: the layers' two-way transmission, exp(-2 tau) of the column (the manual's table:
  // tau 0.478 at 532 nm, 0.334 at 1064 nm, over sea level; over the plane at 900 m less of the
  // molecules, exp(-0.9 / 8) of their 0.1112 and 0.00673).
  ASSERT_EQ(cirrus.transmission.size(), static_cast<std::size_t>(shots * bands));
  const double column[bands] = {0.478 - 0.1112 * (1.0 - std::exp(-0.9 / 8.0)),
                                0.334 - 0.00673 * (1.0 - std::exp(-0.9 / 8.0))};
  for (int k = 0; k < shots * bands; ++k) {
    EXPECT_NEAR(cirrus.transmission[k], std::exp(-2.0 * column[k % bands]), 0.003) << k;
    EXPECT_GT(cirrus.scattered[k], clear.scattered[k]) << k;
    EXPECT_GT(cirrus.delay_m[k], 0.0) << k;
  }
  EXPECT_EQ(cirrus.delay_units, "m");
}

// Without an atmosphere section, shots.nc has none of the atmosphere's truth.
TEST_F(AtmosphereRun, WithoutAnAtmosphereNoTruthIsWritten) {
  const Returns none = run("none");
  EXPECT_TRUE(none.transmission.empty());
  EXPECT_TRUE(none.scattered.empty());
  EXPECT_TRUE(none.delay_m.empty());
}

TEST_F(AtmosphereRun, StratusScattersForwardAndLate) {
  const Returns clear = run("clear");
  const Returns stratus = run("stratus");
  // A stratus of tau 2 from 500 m to 1500 m above the plane sends most of what it scatters
  // forward (g 0.85) into the field of view, which spans 0.24 rad from its base: the return is
  // more than the exp(-4) = 1.8 % that crosses it straight, less than the clear one, and it
  // comes back later, on paths up to R^2 / (2 H) = 14 m longer each way from the base alone
  // (several ns; the Monte Carlo noise of the mean time is 0.03 ns).
  for (int k = 0; k < shots * bands; ++k) {
    const double ratio = stratus.energy_J[k] / clear.energy_J[k];
    EXPECT_GT(ratio, 1.5 * std::exp(-4.0)) << k;
    EXPECT_LT(ratio, 0.2) << k;
    EXPECT_GT(stratus.mean_ns[k] - clear.mean_ns[k], 2.0) << k;
    // The truth's delay is the waveform's later mean time (two-way path over c, 1 ns bins),
    // and most of the stratus's return is scattered light: the direct exp(-4) is under 1/1.5
    // of it.
    const double c_m_ns = 0.299792458;
    EXPECT_NEAR((stratus.delay_m[k] - clear.delay_m[k]) / c_m_ns,
                stratus.mean_ns[k] - clear.mean_ns[k],
                0.1 + 0.03 * (stratus.mean_ns[k] - clear.mean_ns[k]))
        << k;
    EXPECT_GT(stratus.scattered[k], 1.0 - 1.0 / 1.5) << k;
  }
}

// GEDI L2A's sensitivity and quality flag of four shots over the Table 1 forest with a little
// detector noise (0.2 nW RMS), through `clear` and through `stratus`.
struct GediShots {
  std::vector<double> energy_J;  // [shot], shots.nc's rx_energy (the truth, without noise)
  std::vector<float> sensitivity;
  std::vector<std::uint8_t> quality;
};

GediShots gedi_shots(const fs::path& dir, const std::string& atmosphere) {
  const nlohmann::json config = {
      {"seed", 7},
      {"sensor", {{"preset", "gedi"}}},
      {"atmosphere", atmosphere},
      {"detector", {{"enabled", true}, {"noise_rms_W", 2e-10}}},
      {"simulation", {{"rays_per_shot", 2000}}},
      {"terrain",
       {{"plane", {{"origin_lat_deg", 0.0}, {"origin_lon_deg", 0.0}, {"elevation_m", 0.0}}},
        {"soil_reflectance", 0.15}}},
      {"canopy", nlohmann::json::object()},
      {"track",
       {{"type", "pass"},
        {"start_lat_deg", 0.0},
        {"start_lon_deg", 0.0},
        {"heading_deg", 0.0},
        {"shots", 4},
        {"spacing_m", 60.0},
        {"altitude_m", 420000.0}}},
      {"output", {{"netcdf", true}, {"footprints", false}, {"gedi_l2a", true}}}};
  const fs::path file = dir / ("gedi_" + atmosphere + ".json");
  std::ofstream(file) << config.dump(2);
  const fs::path out = dir / ("gedi_" + atmosphere);
  const auto outcome = run_glaswave("run " + file.string() + " --out " + out.string());
  EXPECT_EQ(outcome.status, 0) << outcome.output;
  GediShots g;
  int nc = -1, var = -1;
  EXPECT_EQ(nc_open((out / "shots.nc").c_str(), NC_NOWRITE, &nc), NC_NOERR);
  g.energy_J.resize(4);
  EXPECT_EQ(nc_inq_varid(nc, "rx_energy", &var), NC_NOERR);
  EXPECT_EQ(nc_get_var_double(nc, var, g.energy_J.data()), NC_NOERR);
  nc_close(nc);
  const hid_t h5 = H5Fopen((out / "gedi_l2a.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  EXPECT_GE(h5, 0);
  g.sensitivity.resize(4);
  g.quality.resize(4);
  hid_t set = H5Dopen2(h5, "/BEAM0101/sensitivity", H5P_DEFAULT);
  H5Dread(set, H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, g.sensitivity.data());
  H5Dclose(set);
  set = H5Dopen2(h5, "/BEAM0101/quality_flag", H5P_DEFAULT);
  H5Dread(set, H5T_NATIVE_UINT8, H5S_ALL, H5S_ALL, H5P_DEFAULT, g.quality.data());
  H5Dclose(set);
  H5Fclose(h5);
  return g;
}

// The stratus dims the return some 30 times, and GEDI's sensitivity, 1 - k sigma_noise sqrt(2 pi)
// sigma_pulse / E, falls with the energy E: 1 - (1 - S_clear) E_clear / E_stratus, the energies
// the truth's (0.99 clear, about 0.77 through the stratus). Tolerance 0.12: the noise of E summed
// over the 1420 bins is 7.5 counts in about 55 (0.2 counts a bin), 0.03 of sensitivity; the
// noise level estimated from each waveform's own tails moves it as much again.
TEST_F(AtmosphereRun, GediSensitivityFallsThroughStratus) {
  const GediShots clear = gedi_shots(dir_.path(), "clear");
  const GediShots stratus = gedi_shots(dir_.path(), "stratus");
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_GT(clear.sensitivity[k], 0.98) << k;
    const double expected =
        std::max(0.0, 1.0 - (1.0 - clear.sensitivity[k]) * clear.energy_J[k] / stratus.energy_J[k]);
    EXPECT_LT(expected, 0.9) << k;
    EXPECT_NEAR(stratus.sensitivity[k], expected, 0.12) << k;
    EXPECT_LE(stratus.quality[k], clear.quality[k]) << k;
  }
}

}  // namespace
}  // namespace glaswave
