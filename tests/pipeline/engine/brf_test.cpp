// PHYSICS.md section 5: over a scene, the integrated and normalised waveform of lidar footprints
// (the seed's eq. 1, reflectance / f_fov) is an unbiased estimate of the scene's BRF in the retro
// direction that `brf` computes; and run_brf's products in memory.
#include "pipeline/engine/brf.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "tests/pipeline/engine/engine_test_support.hpp"
#include "tests/terrain/dem_fixture.hpp"

namespace glaswave {
namespace {

// A homogeneous layer (PAI 3, 10 m deep, finite spherical leaves) on level soil, under lidar
// shots at nadir at `shots` places 50 m apart, and under the sun at zenith, seen at nadir. brf
// follows every order; the lidar follows 60 (what orders beyond carry, at most (0.85)^60 of the
// light, is far below the statistics), so that both count the same light.
nlohmann::json layer_scene(int shots) {
  nlohmann::json points = nlohmann::json::array();
  for (int k = 0; k < shots; ++k) points.push_back({{"lat_deg", 0.00045 * k}, {"lon_deg", 0.0}});
  nlohmann::json document = test_support::layer_shot(3.0, 0.05, 0.45, 0.4, 0.3, 60, 2000);
  document["seed"] = 11;
  document["track"]["points"] = points;
  document["output"] = {{"netcdf", false}, {"footprints", false}};
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

// PHYSICS.md section 4 through `glaswave brf` as configured (simulation.max_order at its default
// of 8, the lidar's): leaves that absorb nothing (rho + tau = 1, PAI 5) over white soil on a
// periodic tile send back all the light, so the albedo is 1. Every photon keeps its weight 1
// (roulette never plays), so it is 1 less the photons lost wandering level across 1000 tiles:
// to 0.5 %. brf cut at the lidar's 8 orders gave 0.709 on the scene (issue 28).
TEST(Brf, FollowsEveryOrderSoAConservativeSceneHasAlbedoOne) {
  nlohmann::json document = layer_scene(1);
  document["canopy"]["pai"] = 5.0;
  document["canopy"]["leaf_reflectance"] = 0.6;
  document["canopy"]["leaf_transmittance"] = 0.4;
  document["terrain"]["soil_reflectance"] = 1.0;
  document["brf"]["photons"] = 4000;
  document["brf"]["sun_zenith_deg"] = 30.0;
  document["simulation"].erase("max_order");
  const Config config = parse_config(document);
  ASSERT_EQ(config.simulation.max_order, 8);
  const BrfSummary brf = run_brf(config, {}, nullptr);
  const double albedo = brf.document["bands"][0]["albedo"].get<double>();
  RecordProperty("albedo", std::to_string(albedo));
  EXPECT_NEAR(albedo, 1.0, 0.005);
}

// Over a DEM the tile is not periodic: it must lie on the terrain's data, or the sunlight falling
// beyond the data passes through the scene and is lost. Bare level soil of reflectance 0.3 sends
// back exactly 0.3 of the light that reaches it (each photon meets it once, Lambertian, and
// leaves upward): the albedo of a tile on the DEM. A tile of 300 m over a DEM of 200 m was traced
// as well, giving 0.3 times the part of it on the DEM (0.125; a 300 m tile over share/vegetation's
// 200 m point cloud gave 0.112 against 0.251 on a wider DEM): it is refused.
TEST(Brf, OverADemTheTileMustLieOnTheTerrainsData) {
  const testing::TempFolder dir("glaswave_brf_dem_test");
  testing::RasterSpec spec;
  spec.crs = "EPSG:4326";
  const double half_deg = 0.0009, cell_deg = 0.00002;  // about 200 m across, 2.2 m cells
  spec.width = spec.height = static_cast<int>(std::lround(2.0 * half_deg / cell_deg));
  spec.geotransform = {-half_deg, cell_deg, 0.0, half_deg, 0.0, -cell_deg};
  testing::write_raster(dir / "level.tif", spec, [](int, int, int) { return 100.0; });
  nlohmann::json document = layer_scene(1);
  document["canopy"] = nullptr;
  document["terrain"] = {{"dem", (dir / "level.tif").string()}, {"soil_reflectance", 0.3}};
  document["brf"]["photons"] = 2000;
  document["brf"]["scene_size_m"] = 100.0;
  const BrfSummary inside = run_brf(parse_config(document), {}, nullptr);
  EXPECT_NEAR(inside.document["bands"][0]["albedo"].get<double>(), 0.3, 1e-9);
  // check, whose configuration may be meant for run alone, warns where brf refuses.
  const auto brf_warnings = [&] {
    nlohmann::json for_run = document;  // check asks run's products too
    for_run["output"]["netcdf"] = true;
    std::vector<std::string> found;
    for (const std::string& warning : check_inputs(parse_config(for_run)).warnings)
      if (warning.starts_with("brf would refuse")) found.push_back(warning);
    return found;
  };
  EXPECT_THAT(brf_warnings(), ::testing::IsEmpty());

  document["brf"]["scene_size_m"] = 300.0;
  EXPECT_THAT(brf_warnings(),
              ::testing::ElementsAre(::testing::StartsWith(
                  "brf would refuse this configuration: /brf/scene_size_m: the tile of 300 m")));
  try {
    const BrfSummary beyond = run_brf(parse_config(document), {}, nullptr);
    ADD_FAILURE() << "a 300 m tile over a 200 m DEM was traced: albedo "
                  << beyond.document["bands"][0]["albedo"].get<double>();
  } catch (const Error& e) {
    EXPECT_THAT(std::string(e.what()),
                ::testing::StartsWith("/brf/scene_size_m: the tile of 300 m around the track's "
                                      "first footprint reaches beyond the terrain's data"));
  }
}

}  // namespace
}  // namespace glaswave
