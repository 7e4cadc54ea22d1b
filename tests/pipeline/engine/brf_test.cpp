// PHYSICS.md section 5: over a scene, the integrated and normalised waveform of lidar footprints
// (the seed's eq. 1, reflectance / f_fov) is an unbiased estimate of the scene's BRF in the retro
// direction that `brf` computes; and run_brf's products in memory.
#include "pipeline/engine/brf.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "tests/pipeline/engine/engine_test_support.hpp"

namespace glaswave {
namespace {

// A homogeneous layer (PAI 3, 10 m deep, finite spherical leaves) on level soil, under lidar
// shots at nadir at `shots` places 50 m apart, and under the sun at zenith, seen at nadir.
nlohmann::json layer_scene(int shots) {
  nlohmann::json points = nlohmann::json::array();
  for (int k = 0; k < shots; ++k) points.push_back({{"lat_deg", 0.00045 * k}, {"lon_deg", 0.0}});
  nlohmann::json document = test_support::layer_shot(3.0, 0.05, 0.45, 0.4, 0.3, 8, 2000);
  document["seed"] = 11;
  document["track"]["points"] = points;
  document["output"] = {{"netcdf", false}, {"geojson", false}};
  document["brf"] = {{"sun_zenith_deg", 0.0},
                     {"views", {{{"zenith_deg", 0.0}, {"azimuth_deg", 0.0}}}},
                     {"photons", 30000},
                     {"scene_size_m", 40.0}};
  return document;
}

// Each footprint's reflectance over f_fov against the retro BRF: their difference within three
// of its standard errors (the footprints' scatter over their number, and the BRF's own).
TEST(Brf, WaveformReflectanceIsAnUnbiasedEstimateOfTheRetroBrf) {
  const nlohmann::json document = layer_scene(8);
  const test_support::SimulatedTrack run = test_support::simulate_track(document);
  const SensorSettings& s = run.config.sensor;
  const double f_fov = 1.0 - std::exp(-s.ifov_rad * s.ifov_rad /
                                      (8.0 * s.divergence_sigma_rad * s.divergence_sigma_rad));
  double sum = 0.0, sum_sq = 0.0;
  for (const ShotRecord& record : run.records) {
    const double reflectance = record.reflectance.at(0) / f_fov;
    sum += reflectance;
    sum_sq += reflectance * reflectance;
  }
  const double n = static_cast<double>(run.records.size());
  const double mean = sum / n,
               sd = std::sqrt(std::max(0.0, sum_sq / n - mean * mean) * n / (n - 1));

  const BrfSummary brf = run_brf(parse_config(document), {}, nullptr);
  const auto& view = brf.document["bands"][0]["views"][0];
  const double retro = view["brf"].get<double>(), stderr_ = view["brf_stderr"].get<double>();
  EXPECT_GT(retro, 0.2);
  EXPECT_LT(stderr_, 0.01 * retro);
  EXPECT_NEAR(mean, retro, 3.0 * std::hypot(sd / std::sqrt(n), stderr_))
      << "waveform " << mean << " +- " << sd << " over " << n << " footprints";
}

}  // namespace
}  // namespace glaswave
