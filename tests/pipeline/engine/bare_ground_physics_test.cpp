// PHYSICS.md sections 1 and 2: a shot over bare Lambertian ground against closed-form answers.
// Expected values are computed here from the formulas, independently of the simulation.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "footprints/track.hpp"
#include "pipeline/engine/inputs.hpp"
#include "tests/pipeline/engine/engine_test_support.hpp"

namespace glaswave {
namespace {

constexpr double c_m_s = 299792458.0;
constexpr double pi = std::numbers::pi;

struct Simulated {
  ShotRecord record;
  std::vector<double> bin_time_ns;
};

// The one shot of a points track.
Simulated simulate(const nlohmann::json& document) {
  test_support::SimulatedTrack run = test_support::simulate_track(document);
  return {run.records.at(0), run.bin_time_ns};
}

using test_support::Moments;
using test_support::waveform_moments;

// PHYSICS.md section 1: E_rec = E_t T A_T rho_s cos(alpha) f_fov / (pi R^2),
// f_fov = 1 - exp(-ifov^2 / (8 sigma^2)); Table 2 of the seed at nadir over level ground.
TEST(BareGround, ReceivedEnergyMatchesLambertianFormulaAtNadir) {
  const Simulated shot = simulate(test_support::plane_shot("north2010", 0.0, 0.0, 10000));
  const double f_fov = 1.0 - std::exp(-0.0004 * 0.0004 / (8.0 * 0.00011 * 0.00011));
  EXPECT_NEAR(f_fov, 0.808, 0.001);  // the number PHYSICS.md quotes, to its three digits
  const double range_m = 600000.0;
  EXPECT_NEAR(shot.record.range_m, range_m, 0.01);
  const double energy_mJ[] = {32.0, 72.0}, transmission[] = {0.8, 0.9};
  for (int band = 0; band < 2; ++band) {
    const double expected_J = energy_mJ[band] * 1e-3 * transmission[band] * 0.709 * 0.15 * f_fov /
                              (pi * range_m * range_m);
    EXPECT_NEAR(shot.record.rx_energy_J[band] / expected_J, 1.0, 0.005) << "band " << band;
    // Seed eq. (1) returns rho_s f_fov.
    EXPECT_NEAR(shot.record.reflectance[band] / (0.15 * f_fov), 1.0, 0.005) << "band " << band;
    // Bare ground: no canopy return, and the ground's own waveform (accumulated apart from the
    // total) holds the closed form's energy.
    EXPECT_EQ(shot.record.rx_energy_canopy_J[band], 0.0);
    EXPECT_NEAR(shot.record.rx_energy_ground_J[band] / expected_J, 1.0, 0.005) << "band " << band;
  }
}

// A uniform beam (RAMI-IV's lidar footprint) over level ground: the same closed form with
// f_fov the part of the beam the view sees, the ratio of the cones' solid angles: 1 when the view
// holds the whole beam, (h / a)^2 when it is narrower (half-angles h of the view, a = 2 sigma of
// the beam). Every ray of the first path scores rho_s exactly, so only round-off is allowed.
TEST(BareGround, AUniformBeamReturnsThePartOfItsConeTheViewSees) {
  const double range_m = 600000.0;
  for (const double sigma_rad : {0.00005, 0.0004}) {
    nlohmann::json document = test_support::plane_shot("north2010", 0.0, 0.0, 2000);
    document["sensor"]["beam_profile"] = "uniform";
    document["sensor"]["divergence_sigma_rad"] = sigma_rad;
    const Simulated shot = simulate(document);
    const double a = 2.0 * sigma_rad, h = 0.0002;
    const double f_fov = a <= h ? 1.0 : (h / a) * (h / a);
    const double energy_mJ[] = {32.0, 72.0}, transmission[] = {0.8, 0.9};
    for (int band = 0; band < 2; ++band) {
      const double expected_J = energy_mJ[band] * 1e-3 * transmission[band] * 0.709 * 0.15 * f_fov /
                                (pi * range_m * range_m);
      EXPECT_NEAR(shot.record.rx_energy_J[band] / expected_J, 1.0, 1e-6)
          << "sigma " << sigma_rad << " band " << band;
    }
  }
}

// Gardner's broadening depends on the beam only through its RMS per axis: a uniform disc of
// radius 2 sigma R has RMS sigma R across the slope, so on a 10 deg plane at nadir the uniform
// beam widens the pulse as the Gaussian of the same sigma does, sigma_p^2 = sigma_tx^2 +
// (2 R sigma_theta tan(alpha) / c)^2 + bin^2 / 12 (20.04 ns in PHYSICS.md's table).
TEST(BareGround, AUniformBeamOnASlopeBroadensThePulseByItsRms) {
  const double sigma_theta = 27.5e-6, range_m = 600000.0, sigma_tx_ns = 5.0;
  nlohmann::json document = test_support::plane_shot("north2010", 10.0, 0.0, 40000);
  document["sensor"]["beam_profile"] = "uniform";
  document["sensor"]["divergence_sigma_rad"] = sigma_theta;
  document["sensor"]["bins"] = 1000;
  const Simulated shot = simulate(document);
  const double spread_ns = 2.0 * range_m * sigma_theta * std::tan(10.0 * pi / 180.0) / c_m_s * 1e9;
  const double expected_ns =
      std::sqrt(sigma_tx_ns * sigma_tx_ns + spread_ns * spread_ns + 1.0 / 12);
  EXPECT_NEAR(expected_ns, 20.04, 0.01);
  const Moments m = waveform_moments(shot.record.rx_waveform_W[1], shot.bin_time_ns);
  EXPECT_NEAR(m.rms_ns / expected_ns, 1.0, 0.02);
}

// A level surface at nadir returns the transmitted pulse (RMS 5 ns, plus the bin's 1/12),
// centred on 2R/c.
TEST(BareGround, LevelSurfaceReturnsThePulseAtTwoRangeOverC) {
  const Simulated shot = simulate(test_support::plane_shot("north2010", 0.0, 0.0, 10000));
  for (int band = 0; band < 2; ++band) {
    const Moments m = waveform_moments(shot.record.rx_waveform_W[band], shot.bin_time_ns);
    EXPECT_NEAR(m.rms_ns, std::sqrt(25.0 + 1.0 / 12.0), 0.02);
    EXPECT_NEAR(m.mean_ns, 0.0, 0.1);
  }
  // The peak bin is the reference return's.
  const auto& waveform = shot.record.rx_waveform_W[0];
  const auto peak = std::max_element(waveform.begin(), waveform.end()) - waveform.begin();
  EXPECT_NEAR(shot.bin_time_ns[peak], 0.0, 0.5);
}

// PHYSICS.md section 2 (Gardner 1992): sigma_p^2 = sigma_tx^2 + (2 R sigma_theta tan(alpha) / c)^2
// + bin^2 / 12 on a plane at nadir, with a field of view that does not clip the beam; the
// energy falls as cos(alpha).
TEST(BareGround, SlopeBroadensThePulseAsGardnerAndDimsAsCosine) {
  const double sigma_theta = 27.5e-6, range_m = 600000.0, sigma_tx_ns = 5.0;
  const double slopes_deg[] = {1.0, 5.0, 10.0, 20.0, 30.0};
  const double quoted_ns[] = {5.36, 10.85, 20.04, 40.38, 63.75};  // PHYSICS.md's table
  double level_energy_J = 0.0;
  for (int k = -1; k < 5; ++k) {
    const double slope_deg = k < 0 ? 0.0 : slopes_deg[k];
    nlohmann::json document = test_support::plane_shot("north2010", slope_deg, 0.0, 40000);
    document["sensor"]["divergence_sigma_rad"] = sigma_theta;
    document["sensor"]["ifov_rad"] = 0.002;
    document["sensor"]["bins"] = 1200;
    const Simulated shot = simulate(document);
    if (k < 0) {
      level_energy_J = shot.record.rx_energy_J[1];
      continue;
    }
    const double slope_term_ns =
        2.0 * range_m * sigma_theta * std::tan(slope_deg * pi / 180.0) / c_m_s * 1e9;
    const double expected_ns =
        std::sqrt(sigma_tx_ns * sigma_tx_ns + slope_term_ns * slope_term_ns + 1.0 / 12.0);
    EXPECT_NEAR(expected_ns, quoted_ns[k], 0.01) << "formula check at " << slope_deg << " deg";
    const Moments m = waveform_moments(shot.record.rx_waveform_W[1], shot.bin_time_ns);
    EXPECT_NEAR(m.rms_ns / expected_ns, 1.0, 0.02) << slope_deg << " deg";
    EXPECT_NEAR(shot.record.rx_energy_J[1] / level_energy_J, std::cos(slope_deg * pi / 180.0),
                0.005)
        << slope_deg << " deg";
    EXPECT_NEAR(shot.record.slope_deg, slope_deg, 0.01);
    EXPECT_NEAR(shot.record.aspect_deg, 90.0, 0.01);
  }
}

// Off nadir over level ground: the local incidence alpha = phi' (the zenith angle of the beam
// at the ground), energy cos(alpha) / R^2 with the slant range.
TEST(BareGround, OffNadirEnergyFollowsIncidenceAndSlantRange) {
  const double off_nadir_deg = 5.0;
  nlohmann::json document = test_support::plane_shot("north2010", 0.0, off_nadir_deg, 10000);
  const Simulated shot = simulate(document);
  // Spherical-Earth geometry, independent of the ellipsoidal code: law of sines.
  const double earth_m = 6378137.0, altitude_m = 600000.0;
  const double phi = off_nadir_deg * pi / 180.0;
  const double incidence = std::asin((earth_m + altitude_m) / earth_m * std::sin(phi));
  const double slant_m = earth_m * std::sin(incidence - phi) / std::sin(phi);
  EXPECT_NEAR(shot.record.range_m / slant_m, 1.0, 1e-4);
  const double range_m = shot.record.range_m;
  const double f_fov = 1.0 - std::exp(-0.0004 * 0.0004 / (8.0 * 0.00011 * 0.00011));
  const double expected_J =
      72e-3 * 0.9 * 0.709 * 0.15 * std::cos(incidence) * f_fov / (pi * range_m * range_m);
  EXPECT_NEAR(shot.record.rx_energy_J[1] / expected_J, 1.0, 0.005);
}

}  // namespace
}  // namespace glaswave
