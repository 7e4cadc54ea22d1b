// The waveform products end to end through ShotSimulator: on a bare plane the ground estimate is
// the plane and nothing grows; over the seed's base forest (Tables 1 and 2) the ground comes out
// under the trees and the height at the highest crown top in the footprint; with the detector on,
// the waveform is noisy, its truth parts are not, and the same shot gives the same noise.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "canopy/forest.hpp"
#include "footprints/track.hpp"
#include "pipeline/engine/inputs.hpp"
#include "tests/pipeline/engine/engine_test_support.hpp"

namespace glaswave {
namespace {

constexpr double kGroundM = 250.0;
constexpr double kLatDeg = 45.0, kLonDeg = 7.0;

// A pass of `shots` nadir shots 100 m apart over a level plane at kGroundM.
nlohmann::json pass_over_plane(int shots) {
  return {
      {"seed", 3},
      {"sensor", {{"preset", "north2010"}}},
      {"simulation", {{"rays_per_shot", 4000}}},
      {"terrain",
       {{"plane",
         {{"origin_lat_deg", kLatDeg}, {"origin_lon_deg", kLonDeg}, {"elevation_m", kGroundM}}}}},
      {"canopy", nullptr},
      {"track",
       {{"type", "pass"},
        {"start_lat_deg", kLatDeg},
        {"start_lon_deg", kLonDeg},
        {"heading_deg", 0.0},
        {"shots", shots},
        {"spacing_m", 100.0}}},
      {"output", {{"netcdf", false}, {"footprints", false}}},
  };
}

using test_support::simulate_track;
using test_support::SimulatedTrack;

// The highest crown top (base + 2 half heights) of the trees standing within `radius_m` of the
// footprint centre, above the ground: what the waveform's leading edge should find.
double highest_crown_top_m(const Forest& forest, const Footprint& footprint, double radius_m) {
  const double lat0 = footprint.ground.lat_deg, lon0 = footprint.ground.lon_deg;
  const double m_per_deg_lat = 111132.9,
               m_per_deg_lon = 111319.5 * std::cos(lat0 * std::numbers::pi / 180.0);
  double top_m = 0.0;
  for (const Tree& tree : forest.trees_near(lat0, lon0, radius_m)) {
    const double d =
        std::hypot((tree.lat_deg - lat0) * m_per_deg_lat, (tree.lon_deg - lon0) * m_per_deg_lon);
    if (d <= radius_m) top_m = std::max(top_m, tree.crown_base_m + 2.0 * tree.crown_half_height_m);
  }
  return top_m;
}

// Bare ground: one Gaussian at the plane; the height (signal begin - ground) is the pulse's rise
// to the 1 %-of-peak threshold through the pulse-wide smoothing, sqrt(sigma_p^2 + sigma_tx^2)
// sqrt(2 ln 100) with sigma_p^2 = sigma_tx^2 + bin^2/12 (PHYSICS.md section 2 at nadir on level
// ground), times c/2; all of the return ground return, truth of bare ground.
TEST(WaveformProducts, BarePlane) {
  const SimulatedTrack run = simulate_track(pass_over_plane(3));
  for (const ShotRecord& r : run.records) {
    for (std::size_t band = 0; band < 2; ++band) {
      SCOPED_TRACE(band);
      EXPECT_EQ(r.n_peaks[band], 1);
      EXPECT_NEAR(r.ground_elev_est_m[band], kGroundM, 0.1);
      const double sigma_tx_ns = run.config.sensor.pulse_sigma_ns;
      const double smoothed_ns = std::sqrt(2.0 * sigma_tx_ns * sigma_tx_ns + 1.0 / 12.0);
      const double rise_m = 0.5 * 0.299792458 * smoothed_ns * std::sqrt(2.0 * std::log(100.0));
      EXPECT_NEAR(r.canopy_height_est_m[band], rise_m, 0.05);
      EXPECT_NEAR(r.rh_m[band][50], 0.0, 0.05);
      EXPECT_NEAR(r.centroid_m[band], kGroundM, 0.05);
      EXPECT_LT(r.sig_end_m[band], kGroundM);
      EXPECT_GT(r.sig_begin_m[band], kGroundM);
      EXPECT_NEAR(r.energy_tr_J[band] / r.rx_energy_J[band], 1.0, 0.01);
      EXPECT_LT(r.waveform_index[band], -0.99);
      EXPECT_NEAR(r.gauss_sigma_ns[band][0], run.config.sensor.pulse_sigma_ns, 0.1);
    }
    EXPECT_EQ(r.cover_true, 0.0);
    EXPECT_EQ(r.pai_true, 0.0);
    EXPECT_EQ(r.canopy_height_true_m, 0.0);
  }
}

// The seed's base forest (Table 1 defaults, crowns 15-36 m above the ground; north2010): over
// 10 footprints, in both bands, the ground estimate within 1 m of the plane in at least 8 (it
// comes out within 0.02 m in all), and the canopy height (signal begin - ground, = rh100) within
// 3 m of the highest crown top within the beam's 1/e^2 radius in at least 8.
TEST(WaveformProducts, BaseForestGroundAndHeight) {
  nlohmann::json document = pass_over_plane(10);
  document["canopy"] = nlohmann::json::object();
  const SimulatedTrack run = simulate_track(document);
  const Forest forest(*run.config.canopy, run.config.seed, run.config.terrain.plane);
  const double radius_m = 2.0 * run.footprints[0].range_m * run.config.sensor.divergence_sigma_rad;
  for (std::size_t band = 0; band < 2; ++band) {
    SCOPED_TRACE(band);
    int ground_ok = 0, height_ok = 0;
    for (std::size_t i = 0; i < run.records.size(); ++i) {
      const ShotRecord& r = run.records[i];
      const double top_m = highest_crown_top_m(forest, run.footprints[i], radius_m);
      EXPECT_GT(top_m, 30.0) << "a tall tree in every footprint";
      ground_ok += std::abs(r.ground_elev_est_m[band] - kGroundM) < 1.0;
      height_ok += std::abs(r.canopy_height_est_m[band] - top_m) < 3.0;
      // 70 % cover of PAI 3: mostly canopy return, some ground.
      EXPECT_GT(r.waveform_index[band], 0.0) << i;
      EXPECT_LT(r.waveform_index[band], 1.0) << i;
      EXPECT_GE(r.n_peaks[band], 2) << i;
      EXPECT_LE(r.rh_m[band][98], r.rh_m[band][100]) << i;
      EXPECT_GT(r.rh_m[band][98], 25.0) << i;
    }
    EXPECT_GE(ground_ok, 8);
    EXPECT_GE(height_ok, 8);
  }
}

// The detector on: rx_waveform carries background and noise, the truth parts stay as they
// were, the ground is still found, and the noise is the same for the same shot.
TEST(WaveformProducts, DetectorNoiseOnTheWaveformOnly) {
  nlohmann::json document = pass_over_plane(2);
  const SimulatedTrack clean = simulate_track(document);
  document["detector"] = {{"enabled", true},      {"background_W", 2e-8}, {"noise_rms_W", 1e-8},
                          {"photon_noise", true}, {"bits", 10},           {"saturation_W", 2e-6}};
  const SimulatedTrack noisy = simulate_track(document);
  const SimulatedTrack again = simulate_track(document);
  for (std::size_t shot = 0; shot < 2; ++shot) {
    const ShotRecord &c = clean.records[shot], &n = noisy.records[shot];
    EXPECT_EQ(n.rx_waveform_W, again.records[shot].rx_waveform_W);
    EXPECT_EQ(n.rx_waveform_ground_W, c.rx_waveform_ground_W);
    EXPECT_EQ(n.rx_waveform_canopy_W, c.rx_waveform_canopy_W);
    EXPECT_NE(n.rx_waveform_W, c.rx_waveform_W);
    for (std::size_t band = 0; band < 2; ++band) {
      SCOPED_TRACE(band);
      EXPECT_NEAR(n.ground_elev_est_m[band], kGroundM, 0.15);
      // The noise raises the threshold, so the rise to it is shorter than without noise.
      EXPECT_GT(n.canopy_height_est_m[band], 0.0);
      EXPECT_LT(n.canopy_height_est_m[band], c.canopy_height_est_m[band] + 0.1);
      // Reflectance counts the energy above the noise: within a few % of the clean one.
      EXPECT_NEAR(n.reflectance[band] / c.reflectance[band], 1.0, 0.05);
      EXPECT_NEAR(n.energy_tr_J[band] / c.energy_tr_J[band], 1.0, 0.05);
    }
  }
}

}  // namespace
}  // namespace glaswave
