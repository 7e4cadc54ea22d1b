// Shots sharing their stretch's scene (issue 25's speed): a photon-counting pass over the seed's
// Table 1 forest traced through each stretch's one scene gives what each shot's own scene gives
// (the second method, the per-shot path every other receiver keeps): the same crowns under the
// beam, the same truth, the same sun, the same returns but for rays grazing a crown's edge.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

#include "footprints/solar_position.hpp"
#include "pipeline/engine/inputs.hpp"
#include "pipeline/shot/footprint_geometry.hpp"
#include "pipeline/shot/stretch_scenes.hpp"
#include "tests/pipeline/atlas_pass.hpp"

namespace glaswave {
namespace {

// One strong beam over the Table 1 forest, the sun 30 degrees from the zenith.
Config atlas_forest(int shots, int rays) {
  nlohmann::json pass = test_support::atlas_pass(shots, rays, 5);
  pass["sensor"]["beams"] = {"gt2l"};
  pass["track"]["start_time"] = "2019-03-20T14:00:00Z";
  return parse_config(pass);
}

std::size_t signal_photons(const ShotRecord& record) {
  std::size_t n = 0;
  for (const std::int32_t c : record.photon_class) n += c != photon_noise ? 1 : 0;
  return n;
}

// 64 shots across the boundary between the first two stretches (shot 256), each simulated in its
// own scene and in its stretch's.
TEST(StretchScene, TracesWhatEachShotsOwnSceneDoes) {
  const Config config = atlas_forest(320, 100);
  const auto terrain = make_terrain(config.terrain);
  const std::unique_ptr<Track> track = plan_track(config, *terrain);
  const auto own = make_shot_simulator(config, *terrain);
  const auto shared = make_shot_simulator(config, *terrain);
  shared->share_scenes_along(*track);
  ASSERT_TRUE(shared->shares_scenes());
  ASSERT_FALSE(own->shares_scenes());
  double energy_own = 0.0, energy_shared = 0.0, photons_own = 0.0, photons_shared = 0.0;
  std::vector<double> cover, pai, height;  // shared - own, a shot
  for (const Footprint& footprint : track->footprints(224, 288)) {
    const ShotRecord a = own->simulate(footprint);
    const ShotRecord b = shared->simulate(footprint);
    // The truth's lines on the stretch's grid against the shot's own: the same integral on grids
    // shifted by under a node (0.41 m). A crown's edge crossing a ring of nodes moves the cover
    // and PAI by a few thousandths, the highest foliage within 2 sigma by a crown top entering
    // the disc or not.
    cover.push_back(b.cover_true - a.cover_true);
    pai.push_back(b.pai_true - a.pai_true);
    height.push_back(b.canopy_height_true_m - a.canopy_height_true_m);
    EXPECT_NEAR(b.cover_true, a.cover_true, 0.02) << footprint.shot_number;
    EXPECT_NEAR(b.pai_true, a.pai_true, 0.02) << footprint.shot_number;
    EXPECT_NEAR(b.pgap_true, a.pgap_true, 0.02) << footprint.shot_number;
    EXPECT_NEAR(b.canopy_height_true_m, a.canopy_height_true_m, 0.3) << footprint.shot_number;
    // The sun interpolated along the stretch against ERFA at the shot (its error against SPA:
    // 0.001 deg).
    EXPECT_NEAR(b.solar_elevation_deg, a.solar_elevation_deg, 1e-5) << footprint.shot_number;
    EXPECT_NEAR(b.solar_azimuth_deg, a.solar_azimuth_deg, 1e-5) << footprint.shot_number;
    // The footprint's own ground and bins, whatever frame the scene is in.
    EXPECT_EQ(b.slope_deg, a.slope_deg);
    EXPECT_NEAR(b.elev_bin0_m, a.elev_bin0_m, 1e-6);
    EXPECT_NEAR(b.elev_lastbin_m, a.elev_lastbin_m, 1e-6);
    energy_own += a.rx_energy_J.at(0);
    energy_shared += b.rx_energy_J.at(0);
    photons_own += static_cast<double>(signal_photons(a));
    photons_shared += static_cast<double>(signal_photons(b));
  }
  // The grids' differences are noise about zero: their means within 3 standard errors.
  for (const auto* d : {&cover, &pai, &height}) {
    double mean = 0.0, squares = 0.0;
    for (const double x : *d) {
      mean += x;
      squares += x * x;
    }
    const auto n = static_cast<double>(d->size());
    mean /= n;
    EXPECT_NEAR(mean, 0.0, 3.0 * std::sqrt((squares / n - mean * mean) / n));
  }
  // The same rays (keyed by seed, shot and ray) through the same crowns: the returns differ only
  // where a ray grazes an edge the two frames place a float's width apart.
  EXPECT_NEAR(energy_shared / energy_own, 1.0, 1e-3);
  // The signal photons drawn from those means, within the Poisson count's 3 standard deviations.
  EXPECT_GT(photons_own, 100.0);
  EXPECT_NEAR(photons_shared, photons_own, 3.0 * std::sqrt(photons_own));
}

// A stretch's scene is built once and found by each of its shots; the next stretch has its own;
// shots far apart (a points track) share none.
TEST(StretchScene, OneSceneAStretchNoneForShotsFarApart) {
  const Config config = atlas_forest(600, 10);
  const auto terrain = make_terrain(config.terrain);
  const std::unique_ptr<Track> track = plan_track(config, *terrain);
  const auto simulator = make_shot_simulator(config, *terrain);
  const StretchScenes stretches(simulator->scenes(), simulator->lidar(), *track,
                                vegetation_margin_m);
  const auto first = stretches.find(track->footprint(0));
  ASSERT_NE(first, nullptr);
  EXPECT_EQ(stretches.find(track->footprint(255)), first);
  const auto second = stretches.find(track->footprint(256));
  ASSERT_NE(second, nullptr);
  EXPECT_NE(second, first);
  EXPECT_EQ(stretches.find(track->footprint(511)), second);
  EXPECT_EQ(stretches.find(track->footprint(100)), first);  // still held
  // The second stretch's frame is its middle footprint's (shot 384), 179 m north of the first's.
  const Vec3 offset = first->frame.to_local(second->frame.origin());
  EXPECT_NEAR(offset[1], 256 * 0.7, 0.5);

  Config points = config;
  points.track.type = TrackType::points;
  points.track.points = {{10.0, 0.0}, {10.01, 0.0}};  // 1.1 km apart
  const std::unique_ptr<Track> far = plan_track(points, *terrain);
  const StretchScenes none(simulator->scenes(), simulator->lidar(), *far, vegetation_margin_m);
  EXPECT_EQ(none.find(far->footprint(0)), nullptr);
}

// A run writing the ICESat-2 granules alone computes only what they read
// (make_run_shot_simulator): every field they take (the photons, the geolocation, the sun, the
// truth, the flags) is the same bits as make_shot_simulator's, which computes every field; the
// waveform metrics, the slope and aspect fitted under each shot of a shared stretch and the
// beam's outline are left fill, and the waveforms out (the photons are drawn from the energies
// before the pulse, whose sum is the received energy but for the pulse's tails beyond the window).
// A stretch knows which of its shots are on the terrain's data.
TEST(StretchScene, GranulesAloneComputeWhatTheyReadTheSameBits) {
  Config config = atlas_forest(300, 30);
  ASSERT_FALSE(products_read_shot_fields(config.output));
  Config with_netcdf = config;
  with_netcdf.output.netcdf = true;
  EXPECT_TRUE(products_read_shot_fields(with_netcdf.output));
  const auto terrain = make_terrain(config.terrain);
  const std::unique_ptr<Track> track = plan_track(config, *terrain);
  const auto every = make_shot_simulator(config, *terrain);
  const auto granules = make_run_shot_simulator(config, *terrain);
  every->share_scenes_along(*track);
  granules->share_scenes_along(*track);
  ASSERT_TRUE(granules->shares_scenes());
  for (const Footprint& footprint : track->footprints(240, 270)) {
    std::int64_t queries_every = 0, queries_granules = 0;
    const ShotRecord a = every->simulate(footprint, &queries_every);
    const ShotRecord b = granules->simulate(footprint, &queries_granules);
    EXPECT_EQ(queries_granules, queries_every - outline_vertices);
    EXPECT_EQ(b.photon_time_ns, a.photon_time_ns);
    EXPECT_EQ(b.photon_h_m, a.photon_h_m);
    EXPECT_EQ(b.photon_lat_deg, a.photon_lat_deg);
    EXPECT_EQ(b.photon_lon_deg, a.photon_lon_deg);
    EXPECT_EQ(b.photon_class, a.photon_class);
    EXPECT_EQ(b.photon_order, a.photon_order);
    EXPECT_EQ(b.lat_deg, a.lat_deg);
    EXPECT_EQ(b.lon_deg, a.lon_deg);
    EXPECT_EQ(b.elev_m, a.elev_m);
    EXPECT_EQ(b.solar_elevation_deg, a.solar_elevation_deg);
    EXPECT_EQ(b.cover_true, a.cover_true);
    EXPECT_EQ(b.pai_true, a.pai_true);
    EXPECT_EQ(b.pgap_true, a.pgap_true);
    EXPECT_EQ(b.canopy_height_true_m, a.canopy_height_true_m);
    EXPECT_FALSE(a.rx_waveform_W.empty());
    EXPECT_TRUE(b.rx_waveform_W.empty());
    EXPECT_TRUE(b.rx_waveform_canopy_W.empty());
    EXPECT_NEAR(b.rx_energy_J.at(0), a.rx_energy_J.at(0), 1e-9 * a.rx_energy_J.at(0));
    EXPECT_GT(b.rx_energy_J.at(0), 0.0);
    EXPECT_EQ(b.quality_flag, a.quality_flag);
    EXPECT_EQ(b.quality_reason, a.quality_reason);
    EXPECT_GE(a.n_peaks.at(0), 1);
    EXPECT_EQ(b.n_peaks.at(0), 0);
    EXPECT_TRUE(std::isnan(b.energy_tr_J.at(0)));
    EXPECT_TRUE(std::isfinite(a.slope_deg));
    EXPECT_TRUE(std::isnan(b.slope_deg));
    EXPECT_TRUE(std::isnan(b.aspect_deg));
    EXPECT_FALSE(a.footprint_lonlat.empty());
    EXPECT_TRUE(b.footprint_lonlat.empty());
  }
  const StretchScenes stretches(every->scenes(), every->lidar(), *track, vegetation_margin_m);
  const auto first = stretches.find(track->footprint(0));
  ASSERT_NE(first, nullptr);
  EXPECT_TRUE(first->holds(0));
  EXPECT_TRUE(first->holds(255));
  EXPECT_FALSE(first->holds(256));
  EXPECT_FALSE(first->holds(-1));
}

}  // namespace
}  // namespace glaswave
