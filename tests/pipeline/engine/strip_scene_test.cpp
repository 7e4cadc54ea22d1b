// Waveform shots sharing a strip's scene (issue 39): GEDI's footprints 60 m apart over the seed's
// Table 1 forest on a rough plane, on a pass, an orbit and a line of points, traced through each
// strip's one scene, give what each shot's own scene gives (the second method, the per-shot path
// that footprints far apart keep): the same returns within the Monte Carlo's noise, the same truth
// within the grids' spacing, the same sun and ground fit; a strip's scene depends on the strip
// alone, whichever shot builds it; points scattered about, and a lone point, keep their own.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <numbers>
#include <optional>
#include <vector>

#include "footprints/orbit.hpp"
#include "pipeline/engine/inputs.hpp"
#include "pipeline/engine/machine.hpp"
#include "pipeline/shot/footprint_geometry.hpp"
#include "pipeline/shot/forest_source.hpp"
#include "pipeline/shot/stretch_scenes.hpp"
#include "terrain/local_frame.hpp"
#include "tests/terrain/dem_fixture.hpp"

namespace glaswave {
namespace {

// One GEDI beam 60 m a shot at 30 degrees east of north (a strip turned in its frame) over the
// Table 1 forest on a 10 degree plane with roughness of 0.2 m RMS, 3 m correlation.
Config gedi_pass(int shots, int rays) {
  const nlohmann::json pass = {
      {"seed", 11},
      {"sensor", {{"preset", "gedi"}}},
      {"simulation", {{"rays_per_shot", rays}, {"max_order", 3}}},
      {"terrain",
       {{"plane",
         {{"origin_lat_deg", 10.0},
          {"origin_lon_deg", 0.0},
          {"elevation_m", 100.0},
          {"slope_deg", 10.0},
          {"aspect_deg", 200.0}}},
        {"roughness", {{"rms_m", 0.2}, {"correlation_m", 3.0}}},
        {"soil_reflectance", 0.25}}},
      {"canopy", nlohmann::json::object()},
      {"track",
       {{"type", "pass"},
        {"start_lat_deg", 10.0},
        {"start_lon_deg", 0.0},
        {"heading_deg", 30.0},
        {"shots", shots},
        {"spacing_m", 60.0},
        {"altitude_m", 420000.0},
        {"start_time", "2019-03-20T14:00:00Z"}}},
      {"output", {{"netcdf", true}, {"footprints", false}}},
  };
  return parse_config(pass);
}

// The same beam's 24 footprints, 60 m apart at 30 degrees east of north from (10 N, 0 E), as
// points.
Config gedi_points(int rays) {
  Config config = gedi_pass(24, rays);
  const auto terrain = make_terrain(config.terrain);
  const std::unique_ptr<Track> pass = plan_track(config, *terrain);
  config.track.type = TrackType::points;
  config.track.points.clear();
  for (const Footprint& footprint : pass->footprints(0, 24))
    config.track.points.push_back({footprint.ground.lat_deg, footprint.ground.lon_deg});
  return config;
}

// GEDI's orbit (420 km, 51.6 degrees; a beam's 121 shots a second, 57 m apart), its 24 shots
// from 300 s after the epoch over a level rough plane anchored under the first.
Config gedi_orbit(int rays) {
  OrbitElements elements;
  elements.semi_major_axis_m = 6378137.0 + 420000.0;
  elements.inclination_deg = 51.6;
  elements.raan_deg = 30.0;
  const Geodetic under = geodetic_from_ecef(Orbit(elements).ecef_position_m(300.0));
  Config config = gedi_pass(24, rays);
  config.terrain.plane->origin_lat_deg = under.lat_deg;
  config.terrain.plane->origin_lon_deg = under.lon_deg;
  config.terrain.plane->slope_deg = 0.0;
  config.track.type = TrackType::orbit;
  config.track.orbit = elements;
  config.track.rate_hz = 121.0;
  config.track.start_time_s = 300.0;
  config.track.shots = 24;
  return config;
}

double mean_of(const std::vector<double>& d, double* standard_error) {
  double mean = 0.0, squares = 0.0;
  for (const double x : d) {
    mean += x;
    squares += x * x;
  }
  const auto n = static_cast<double>(d.size());
  mean /= n;
  *standard_error = std::sqrt((squares / n - mean * mean) / n);
  return mean;
}

// 24 shots, three strips, each simulated in its own scene and in its strip's.
void expect_strips_trace_what_own_scenes_do(const Config& config) {
  const auto terrain = make_terrain(config.terrain);
  const std::unique_ptr<Track> track = plan_track(config, *terrain);
  const auto own = make_shot_simulator(config, *terrain);
  auto shared = make_shot_simulator(config, *terrain);
  ASSERT_EQ(shot_settings(config).strip_shots, strip_shots);
  shared->share_scenes_along(*track);
  ASSERT_TRUE(shared->shares_strips());
  ASSERT_FALSE(shared->shares_scenes());  // the engine's small batches: shots of milliseconds
  Config reseeded = config;
  reseeded.seed = config.seed + 1;
  const auto other_draw = make_shot_simulator(reseeded, *terrain);
  std::vector<double> energy, ground, cover, pai, height;  // shared - own, a shot
  std::vector<double> energy_draw;                         // another seed's - own, a shot
  double energy_own = 0.0;
  for (const Footprint& footprint : track->footprints(0, 24)) {
    const ShotRecord a = own->simulate(footprint);
    const ShotRecord b = shared->simulate(footprint);
    ASSERT_EQ(a.quality_flag, b.quality_flag);
    // The same rays (keyed by seed, shot and ray) through the same crowns and the same relief
    // under the beam (the lattice is the zone's: within 3 mm): the returns differ where a ray
    // grazes an edge the two frames place a float's width apart, lands a few millimetres off on
    // the rough ground and leaves it another way, or wanders beyond 100 m into crowns one scene
    // holds and the other not (or beyond 4.5 sigma, onto relief a strip meshes for its
    // neighbours). A shot's return then differs by a few per cent at 400 rays (up to 3.4 % on
    // the orbit; the same bits without roughness), far less than another draw's: the Monte
    // Carlo's own noise, measured by the shot with another seed.
    const ShotRecord c = other_draw->simulate(footprint);
    energy.push_back(b.rx_energy_J.at(0) - a.rx_energy_J.at(0));
    ground.push_back(b.rx_energy_ground_J.at(0) - a.rx_energy_ground_J.at(0));
    energy_draw.push_back(c.rx_energy_J.at(0) - a.rx_energy_J.at(0));
    energy_own += a.rx_energy_J.at(0);
    // The truth's lines on the strip's grid against the shot's own: grids a fraction of a node
    // (0.9 m) apart.
    cover.push_back(b.cover_true - a.cover_true);
    pai.push_back(b.pai_true - a.pai_true);
    height.push_back(b.canopy_height_true_m - a.canopy_height_true_m);
    EXPECT_NEAR(b.cover_true, a.cover_true, 0.03) << footprint.shot_number;
    EXPECT_NEAR(b.pai_true, a.pai_true, 0.05) << footprint.shot_number;
    // The sun interpolated along the strip against ERFA at the shot.
    EXPECT_NEAR(b.solar_elevation_deg, a.solar_elevation_deg, 1e-5);
    EXPECT_NEAR(b.solar_azimuth_deg, a.solar_azimuth_deg, 1e-5);
    // The footprint's own ground fit and bins, whatever frame the scene is in.
    EXPECT_EQ(b.slope_deg, a.slope_deg);
    EXPECT_NEAR(b.elev_bin0_m, a.elev_bin0_m, 1e-6);
    EXPECT_NEAR(b.elev_lastbin_m, a.elev_lastbin_m, 1e-6);
  }
  // The differences are noise about zero: their means within 3 standard errors.
  for (const auto* d : {&energy, &ground, &cover, &pai, &height}) {
    double standard_error = 0.0;
    const double mean = mean_of(*d, &standard_error);
    EXPECT_LE(std::abs(mean), 3.0 * standard_error + 1e-12 * energy_own);
  }
  // A strip's shot is its own scene's twin: far closer to it than another draw is.
  auto rms = [](const std::vector<double>& d) {
    double squares = 0.0;
    for (const double x : d) squares += x * x;
    return std::sqrt(squares / static_cast<double>(d.size()));
  };
  EXPECT_LT(rms(energy), 0.25 * rms(energy_draw));
}

TEST(StripScene, TracesWhatEachShotsOwnSceneDoesOnAPass) {
  expect_strips_trace_what_own_scenes_do(gedi_pass(24, 400));
}

TEST(StripScene, TracesWhatEachShotsOwnSceneDoesOnAnOrbit) {
  expect_strips_trace_what_own_scenes_do(gedi_orbit(400));
}

TEST(StripScene, TracesWhatEachShotsOwnSceneDoesOnPoints) {
  expect_strips_trace_what_own_scenes_do(gedi_points(400));
}

// Points scattered about build their own scenes: 8 points, the first two 60 m apart, the others
// out to 450 m each way from the middle one (within the 500 m a strip may reach), would share a
// rectangle about 1.25 km square, 1.5 times their own 355 m squares together. The same 8
// points along a line share one; a lone point keeps its own scene, as before strips.
TEST(StripScene, PointsScatteredAboutAndALonePointKeepTheirOwnScenes) {
  Config config = gedi_points(50);
  config.track.points.clear();
  const double east_m[] = {-450, -390, 0, 0, 0, 0, 450, 390};
  const double north_m[] = {0, 0, 450, 390, 0, -450, 0, 0};
  for (int k = 0; k < 8; ++k)
    config.track.points.push_back({10.0 + north_m[k] / 110600.0, east_m[k] / 109640.0});
  const auto terrain = make_terrain(config.terrain);
  const std::unique_ptr<Track> track = plan_track(config, *terrain);
  auto simulator = make_shot_simulator(config, *terrain);
  simulator->share_scenes_along(*track);
  ASSERT_TRUE(simulator->shares_strips());
  EXPECT_EQ(simulator->stretches()->find(track->footprint(0)), nullptr);
  EXPECT_FALSE(simulator->stretches()->plan_strip(0, 0));
  // The same 8 points along a line 60 m apart share one.
  Config line = gedi_points(50);
  line.track.points.resize(8);
  const std::unique_ptr<Track> along = plan_track(line, *terrain);
  simulator = make_shot_simulator(line, *terrain);
  simulator->share_scenes_along(*along);
  EXPECT_NE(simulator->stretches()->find(along->footprint(0)), nullptr);

  line.track.points.resize(1);
  const std::unique_ptr<Track> lone = plan_track(line, *terrain);
  simulator = make_shot_simulator(line, *terrain);
  simulator->share_scenes_along(*lone);
  EXPECT_FALSE(simulator->shares_strips());
}

// A strip's scene is built once for its 8 shots and found by each; the next strip has its own,
// whichever shot of it comes first; the records do not depend on which shot built their scene
// (threads, --shots parts and --resume start anywhere). GLAS's 172 m spacing shares none.
TEST(StripScene, OneSceneAStripThatDependsOnTheStripAlone) {
  const Config config = gedi_pass(24, 50);
  const auto terrain = make_terrain(config.terrain);
  const std::unique_ptr<Track> track = plan_track(config, *terrain);
  const auto simulator = make_shot_simulator(config, *terrain);
  const StretchScenes strips(simulator->scenes(), simulator->lidar(), *track, vegetation_margin_m,
                             strip_shots, StretchShape::strip);
  const auto first = strips.find(track->footprint(0));
  ASSERT_NE(first, nullptr);
  EXPECT_EQ(strips.find(track->footprint(7)), first);
  const auto second = strips.find(track->footprint(8));
  ASSERT_NE(second, nullptr);
  EXPECT_NE(second, first);
  // Its frame is its middle footprint's (shot 12), 8 shots (480 m) up the track from the first's.
  const Vec3 offset = first->frame.to_local(second->frame.origin());
  EXPECT_NEAR(std::hypot(offset[0], offset[1]), 480.0, 0.5);
  EXPECT_NEAR(std::atan2(offset[0], offset[1]) * 180.0 / std::numbers::pi, 30.0, 0.1);

  // The track's shots in order, backwards, and from the middle of a strip on a fresh simulator.
  auto forwards = make_shot_simulator(config, *terrain);
  auto backwards = make_shot_simulator(config, *terrain);
  auto middle = make_shot_simulator(config, *terrain);
  for (auto* s : {&forwards, &backwards, &middle}) (*s)->share_scenes_along(*track);
  std::vector<ShotRecord> a, b(24), c;
  for (std::int64_t shot = 0; shot < 24; ++shot)
    a.push_back(forwards->simulate(track->footprint(shot)));
  for (std::int64_t shot = 23; shot >= 0; --shot)
    b[static_cast<std::size_t>(shot)] = backwards->simulate(track->footprint(shot));
  for (std::int64_t shot = 13; shot < 24; ++shot)
    c.push_back(middle->simulate(track->footprint(shot)));
  for (std::size_t k = 0; k < 24; ++k) {
    EXPECT_EQ(b[k].rx_waveform_W, a[k].rx_waveform_W) << k;
    EXPECT_EQ(b[k].cover_true, a[k].cover_true) << k;
    EXPECT_EQ(b[k].solar_azimuth_deg, a[k].solar_azimuth_deg) << k;
    if (k >= 13) {
      EXPECT_EQ(c[k - 13].rx_waveform_W, a[k].rx_waveform_W) << k;
      EXPECT_EQ(c[k - 13].pai_true, a[k].pai_true) << k;
    }
  }

  Config glas = config;
  glas.track.spacing_m = 172.0;
  const std::unique_ptr<Track> apart = plan_track(glas, *terrain);
  const StretchScenes none(simulator->scenes(), simulator->lidar(), *apart, vegetation_margin_m,
                           strip_shots, StretchShape::strip);
  EXPECT_EQ(none.find(apart->footprint(0)), nullptr);
}

// The memory estimate's strips are the run's, as StretchScenes plans them: 24 shots make 3
// strips of 8, all kept (one beam keeps 5); a strip's rectangle is as wide as a shot's scene and
// 7 spacings (420 m) longer; its rough ground is the beams' squares on the 1 m lattice (3 m
// correlation over 3 nodes), two triangles a square metre, the squares 60 m apart along 30
// degrees overlapping only their neighbours; the forest is the Table 1 canopy's density of
// crowns over the rectangle.
TEST(StripScene, TheMemoryEstimateCountsTheStripsAsPlanned) {
  const Config config = gedi_pass(24, 50);
  const auto terrain = make_terrain(config.terrain);
  const std::unique_ptr<Track> track = plan_track(config, *terrain);
  const auto simulator = make_shot_simulator(config, *terrain);
  EXPECT_FALSE(shared_scenes(*simulator, *track));  // before it follows the track
  simulator->share_scenes_along(*track);
  const std::optional<SharedScenes> shared = shared_scenes(*simulator, *track);
  ASSERT_TRUE(shared);
  EXPECT_EQ(shared->shots, 8);
  EXPECT_EQ(shared->held, 3.0);
  EXPECT_NEAR(shared->length_m - shared->width_m, 420.0, 0.5);
  EXPECT_NEAR(shared->vegetation_side_m * shared->vegetation_side_m,
              shared->length_m * shared->width_m, 1e-6 * shared->length_m * shared->width_m);

  const std::optional<StripPlan> plan = simulator->stretches()->plan_strip(0, 0);
  ASSERT_TRUE(plan);
  ASSERT_EQ(plan->rough.size(), 8u);
  double area_m2 = 0.0;
  for (std::size_t k = 0; k < 8; ++k) {
    const RoughSquare& a = plan->rough[k];
    area_m2 += 4.0 * a.half_size_m * a.half_size_m;
    if (k == 0) continue;
    const RoughSquare& b = plan->rough[k - 1];
    EXPECT_NEAR(std::hypot(a.x_m - b.x_m, a.y_m - b.y_m), 60.0, 0.1);
    ASSERT_LT(a.half_size_m + b.half_size_m, 2.0 * 60.0 * std::cos(std::numbers::pi / 6.0));
    area_m2 -= std::max(0.0, a.half_size_m + b.half_size_m - std::abs(a.x_m - b.x_m)) *
               std::max(0.0, a.half_size_m + b.half_size_m - std::abs(a.y_m - b.y_m));
  }
  // The plane's own mesh is 2 x 2 cells over the square: at most 8 triangles more.
  EXPECT_NEAR(shared->ground.rough_triangles, 2.0 * area_m2, 1e-6 * area_m2);
  EXPECT_LE(shared->ground.terrain_triangles, 8.0);

  const RunMemory strips = estimate_run_memory(config, &*shared);
  const RunMemory own = estimate_run_memory(config);
  const CanopySettings& canopy = *config.canopy;
  const double crowns_m2 = -std::log(1.0 - canopy.cover) /
                           (std::numbers::pi * canopy.crown_radius_m * canopy.crown_radius_m);
  const double strip_bytes = crowns_m2 * shared->length_m * shared->width_m * forest_tree_bytes +
                             shared->ground.terrain_triangles * ground_triangle_bytes +
                             shared->ground.rough_triangles * rough_triangle_bytes;
  EXPECT_NEAR(strips.bytes,
              program_resident_bytes + 3.0 * strip_bytes + own.threads * own.waveform_bytes,
              1e-9 * strips.bytes);
  EXPECT_NEAR(own.bytes - program_resident_bytes,
              own.threads * (own.scene_bytes + own.waveform_bytes), 1e-9 * own.bytes);
}

// An orbit's time sequence runs mostly off a DEM: the estimate plans the strips where its
// records are. 10 s of GEDI's orbit (1,210 shots at 121 a second) over a level DEM 0.02 degrees
// square: 2.2 to 3.1 km of track, 37 to 52 shots on it, 5 to 7 strips of which 5 are kept at
// once; each as a pass's, 7 spacings longer than it is wide. Planned at the sequence's first,
// middle and last strips (off the DEM), the estimate found none and counted a scene a thread.
TEST(StripScene, TheMemoryEstimatePlansAnOrbitsStripsWhereItsShotsAre) {
  Config config = gedi_orbit(50);
  const testing::TempFolder dir("glaswave_strip_orbit_dem_test");
  testing::RasterSpec spec;
  spec.crs = "EPSG:4326";
  const double half_deg = 0.01, cell_deg = 0.0002;
  spec.width = spec.height = static_cast<int>(std::lround(2.0 * half_deg / cell_deg));
  spec.geotransform = {config.terrain.plane->origin_lon_deg - half_deg, cell_deg, 0.0,
                       config.terrain.plane->origin_lat_deg + half_deg, 0.0,      -cell_deg};
  testing::write_raster(dir / "level.tif", spec, [](int, int, int) { return 100.0; });
  config.terrain.plane.reset();
  config.terrain.dem = (dir / "level.tif").string();
  config.track.start_time_s = 292.0;  // the DEM 8 s on, not in the middle
  config.track.shots = 1210;
  const auto terrain = make_terrain(config.terrain);
  const std::unique_ptr<Track> track = plan_track(config, *terrain);
  ASSERT_GE(track->size(), 37);
  ASSERT_LE(track->size(), 52);
  const auto simulator = make_shot_simulator(config, *terrain);
  simulator->share_scenes_along(*track);
  ASSERT_TRUE(simulator->shares_strips());
  const std::optional<SharedScenes> shared = shared_scenes(*simulator, *track);
  ASSERT_TRUE(shared);
  EXPECT_EQ(shared->shots, 8);
  EXPECT_EQ(shared->held, 5.0);
  const Footprint a = track->footprint(0), b = track->footprint(1);
  const Vec3 step = LocalFrame(a.ground).to_local(b.ground);
  EXPECT_NEAR(std::hypot(step[0], step[1]), 60.0, 5.0);  // 57 m: the ground speed over 121 Hz
  EXPECT_NEAR(shared->length_m - shared->width_m, 7.0 * std::hypot(step[0], step[1]), 1.0);
}

}  // namespace
}  // namespace glaswave
