// One ray alone (simulate_ray) and the events an observer sees: the ray re-runs exactly as it
// runs inside its shot, its events add up to its return, and they say where it went.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "canopy/leaf_angles.hpp"
#include "pipeline/transport/shot_transport.hpp"
#include "terrain/ground_mesh.hpp"
#include "tests/pipeline/transport/transport_test_support.hpp"

namespace glaswave {
namespace {

using test_support::table2_sensor;

// E_t T A_T f_fov / (pi R^2) of PHYSICS.md section 1 for Table 2's 532 nm band at 600 km, from
// the table's numbers (A_T = pi 0.95^2 / 4 = 0.709 m^2, ifov 0.4 mrad, sigma 0.11 mrad).
double table2_normalisation_532_J() {
  const double f_fov = 1.0 - std::exp(-0.0004 * 0.0004 / (8.0 * 0.00011 * 0.00011));
  return 32e-3 * 0.8 * 0.709 * f_fov / (std::numbers::pi * 600000.0 * 600000.0);
}

// Two ellipsoid crowns of two kinds of foliage over level ground, seen from 600 km at nadir.
struct TwoCrowns : test_support::CrownScene {
  TwoCrowns()
      : CrownScene({{CrownShape::ellipsoid, {4.0, 0.0, 6.0}, 7.0, 6.0, 0.4, 0},
                    {CrownShape::ellipsoid, {-5.0, 3.0, 3.0}, 6.0, 5.0, 0.5, 1}},
                   {{{0.45, 0.45}, {0.45, 0.45}, {0.3, 0.3}, 0.05},  // broadleaf
                    {{0.1, 0.4}, {0.05, 0.4}, {0.2, 0.3}, 0.0}},     // needles
                   {0.2, 0.25}) {}
};

// Every ray of a shot re-run alone: the shot is the sum of its rays, to round-off (the rays'
// parts are summed in another order). A ray drawing other numbers alone than in its shot would
// miss by the Monte Carlo noise of 256 rays, some per cent.
TEST(SimulateRay, TheRaysAloneAddUpToTheirShot) {
  const TwoCrowns forest;
  const LidarModel lidar(table2_sensor());
  TransportOptions options;
  options.rays = 256;
  options.max_order = 4;
  options.per_order = true;
  const ShotWaveforms shot =
      simulate_shot(*forest.scene, lidar, forest.geometry, forest.optics, options, 9);
  std::vector<double> energy_J(2, 0.0), order2_J(2, 0.0);
  std::int64_t queries = 0;
  for (std::int64_t ray = 0; ray < options.rays; ++ray) {
    const ShotWaveforms alone =
        simulate_ray(*forest.scene, lidar, forest.geometry, forest.optics, options, 9, ray);
    queries += alone.ray_queries;
    for (std::size_t band = 0; band < 2; ++band) {
      energy_J[band] += alone.energy_J[band];
      for (double power_W : alone.order_W[band][1]) order2_J[band] += power_W * 1e-9;
    }
  }
  EXPECT_EQ(queries, shot.ray_queries);
  for (std::size_t band = 0; band < 2; ++band) {
    double shot_order2_J = 0.0;
    for (double power_W : shot.order_W[band][1]) shot_order2_J += power_W * 1e-9;
    ASSERT_GT(shot.canopy_energy_J[band], 0.0);
    ASSERT_GT(shot_order2_J, 0.0);
    EXPECT_NEAR(energy_J[band] / shot.energy_J[band], 1.0, 1e-12) << band;
    EXPECT_NEAR(order2_J[band] / shot_order2_J, 1.0, 1e-12) << band;
  }
}

TEST(SimulateRay, AnObserverChangesNothing) {
  const TwoCrowns forest;
  const LidarModel lidar(table2_sensor());
  TransportOptions options;
  options.rays = 1000;
  int events = 0;
  for (std::int64_t ray : {0, 17, 999}) {
    const ShotWaveforms quiet =
        simulate_ray(*forest.scene, lidar, forest.geometry, forest.optics, options, 4, ray);
    const ShotWaveforms watched = simulate_ray(*forest.scene, lidar, forest.geometry, forest.optics,
                                               options, 4, ray, [&](const RayEvent&) { ++events; });
    EXPECT_EQ(quiet.total_W, watched.total_W);
    EXPECT_EQ(quiet.ray_queries, watched.ray_queries);
  }
  EXPECT_GE(events, 3 * 4);  // at least enter, interaction, score, end a ray
}

// The score events of a ray are its return: their weights times E_t T A_T f_fov / (pi R^2),
// over the shot's rays, add up to the ray's energy (the pulse spreads each into the window
// without loss when it falls well inside).
TEST(SimulateRay, ScoreEventsAddUpToTheRaysEnergy) {
  const TwoCrowns forest;
  const LidarModel lidar(table2_sensor());
  TransportOptions options;
  options.rays = 1000;
  const int margin = (lidar.tally_size() - lidar.bins()) / 2;
  int scores = 0;
  for (std::int64_t ray = 0; ray < 40; ++ray) {
    double weight = 0.0;
    const ShotWaveforms alone =
        simulate_ray(*forest.scene, lidar, forest.geometry, forest.optics, options, 6, ray,
                     [&](const RayEvent& event) {
                       if (event.kind != RayEventKind::score) return;
                       ++scores;
                       ASSERT_GE(event.tally_bin, 2 * margin);  // well inside the window
                       ASSERT_LT(event.tally_bin, lidar.bins());
                       weight += event.weight[0];
                     });
    EXPECT_NEAR(weight * table2_normalisation_532_J() / options.rays, alone.energy_J[0],
                1e-12 * alone.energy_J[0])
        << "ray " << ray;
  }
  EXPECT_GT(scores, 40);
}

// Over a level Lambertian plane at nadir the story is known: the beam path meets the ground
// and scores rho (a Lambertian surface of reflectance rho seen square-on at the reference
// range weighs rho) at the reference time; the second path meets the ground, scatters upward
// carrying rho, and leaves the scene.
TEST(SimulateRay, ALevelPlaneTellsItsStory) {
  const PlaneTerrain plane({0.0, 0.0, 0.0, 0.0, 0.0});
  const LocalFrame frame({0.0, 0.0, 0.0});
  const RayDevice device;
  const Scene scene(device, build_ground_mesh(plane, frame, 200.0, 1.0e9));
  ShotGeometry geometry{{0.0, 0.0, 600000.0}, {0.0, 0.0, -1.0}, 600000.0};
  SceneOptics optics;
  optics.soil_reflectance = {0.15, 0.3};
  const LidarModel lidar(table2_sensor());
  TransportOptions options;
  std::vector<RayEvent> events;
  std::vector<std::vector<double>> weights;
  simulate_ray(scene, lidar, geometry, optics, options, 2, 5, [&](const RayEvent& event) {
    events.push_back(event);
    weights.emplace_back(event.weight.begin(), event.weight.end());
  });
  using K = RayEventKind;
  const std::vector<K> expected = {K::enter, K::interaction, K::score,   K::end,
                                   K::enter, K::interaction, K::scatter, K::leave};
  ASSERT_EQ(events.size(), expected.size());
  for (std::size_t i = 0; i < events.size(); ++i) EXPECT_EQ(events[i].kind, expected[i]) << i;
  EXPECT_NEAR(events[0].position_m[2], 1.0, 1e-6);  // just above the scene
  EXPECT_TRUE(events[0].single_scattering_path);
  EXPECT_FALSE(events[4].single_scattering_path);
  const RayEvent& score = events[2];
  EXPECT_EQ(score.element, RayElement::ground);
  EXPECT_EQ(score.order, 1);
  // The plane follows the ellipsoid: a few millimetres below the tangent plane 200 m out.
  EXPECT_NEAR(score.position_m[2], 0.0, 0.01);
  // Within 0.2 mrad of nadir: cos and (R / L)^2 are 1 to 1e-7.
  EXPECT_NEAR(weights[2][0], 0.15, 1e-6);
  EXPECT_NEAR(weights[2][1], 0.3, 1e-6);
  EXPECT_NEAR(score.path_m, 2.0 * 600000.0, 0.05);
  EXPECT_NEAR(score.time_ns, 0.0, 0.2);
  EXPECT_EQ(score.tally_bin, lidar.tally_index(0.0));
  // The window's bin is the one whose centre is nearest the return's time.
  ASSERT_GE(score.bin, 0);
  EXPECT_NEAR(lidar.bin_time_ns()[score.bin], score.time_ns, 0.5 * lidar.sensor().bin_ns);
  EXPECT_GT(events[6].direction[2], 0.0);  // the scattered path goes up
  EXPECT_EQ(weights[6], optics.soil_reflectance);
}

// A leaf event names the crown it is in and that crown's foliage.
TEST(SimulateRay, LeafEventsNameTheirCrown) {
  const TwoCrowns forest;
  const LidarModel lidar(table2_sensor());
  TransportOptions options;
  options.rays = 1000;
  int seen[2] = {0, 0};
  for (std::int64_t ray = 0; ray < 200; ++ray)
    simulate_ray(*forest.scene, lidar, forest.geometry, forest.optics, options, 1, ray,
                 [&](const RayEvent& event) {
                   if (event.kind != RayEventKind::interaction) return;
                   if (event.element != RayElement::leaf) return;
                   ASSERT_GE(event.crown, 0);
                   ASSERT_LT(event.crown, 2);
                   const Crown& crown = forest.vegetation.crowns[event.crown];
                   EXPECT_EQ(event.foliage, crown.material);
                   const Vec3 d = event.position_m - crown.base_m;
                   const double h = crown.half_height_m, r = crown.radius_m;
                   const double inside =
                       (d[0] * d[0] + d[1] * d[1]) / (r * r) + (d[2] - h) * (d[2] - h) / (h * h);
                   EXPECT_LE(inside, 1.0 + 1e-9);
                   ++seen[event.crown];
                 });
  EXPECT_GT(seen[0], 0);
  EXPECT_GT(seen[1], 0);
}

}  // namespace
}  // namespace glaswave
