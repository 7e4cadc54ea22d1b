// The lidar model (pulse, bins, beam sampling), the determinism of the shot transport, and
// what a ray meets first (a leaf by its free path, or a surface).
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <memory>
#include <numbers>
#include <optional>
#include <vector>

#include "canopy/leaf_angles.hpp"
#include "core/random.hpp"
#include "pipeline/transport/scattering.hpp"
#include "pipeline/transport/shot_transport.hpp"
#include "terrain/ground_mesh.hpp"
#include "tests/pipeline/transport/transport_test_support.hpp"

namespace glaswave {
namespace {

using test_support::table2_sensor;

TEST(LidarModel, PulseConvolutionKeepsEnergyAndHasTheTransmittedWidth) {
  const LidarModel lidar(table2_sensor());
  std::vector<double> tally(lidar.tally_size(), 0.0);
  tally[lidar.tally_index(0.0)] = 2.0e-12;
  const std::vector<double> power = lidar.power_W(tally);
  const std::vector<double> times = lidar.bin_time_ns();
  double energy = 0, first = 0, second = 0;
  for (std::size_t i = 0; i < power.size(); ++i) {
    energy += power[i] * 1e-9;
    first += power[i] * times[i];
    second += power[i] * times[i] * times[i];
  }
  EXPECT_NEAR(energy / 2.0e-12, 1.0, 1e-12);
  EXPECT_NEAR(first / (energy * 1e9), 0.0, 1e-9);  // the reference return sits on a bin centre
  EXPECT_NEAR(std::sqrt(second / (energy * 1e9)), 5.0, 1e-3);
}

TEST(LidarModel, BinsAreOneBinWidthApartAndCoverTheWindow) {
  LidarSettings sensor = table2_sensor();
  sensor.bin_ns = 0.5;
  sensor.bins = 300;
  const LidarModel lidar(sensor);
  const std::vector<double> times = lidar.bin_time_ns();
  ASSERT_EQ(times.size(), 300u);
  for (std::size_t i = 1; i < times.size(); ++i) EXPECT_DOUBLE_EQ(times[i] - times[i - 1], 0.5);
  EXPECT_LT(times.front(), 0.0);
  EXPECT_GT(times.back(), 0.0);
  // A time maps to the bin whose centre is nearest.
  const int margin = (lidar.tally_size() - sensor.bins) / 2;
  EXPECT_EQ(lidar.tally_index(times[17] + 0.2) - margin, 17);
  EXPECT_EQ(lidar.tally_index(times[17] - 0.2) - margin, 17);
  EXPECT_EQ(lidar.tally_index(-1.0e6), -1);
}

TEST(LidarModel, TransmittedPulseCarriesThePulseEnergy) {
  const LidarModel lidar(table2_sensor());
  double energy_J = 0;
  for (double power_W : lidar.tx_waveform_W(1)) energy_J += power_W * 1e-9;
  EXPECT_NEAR(energy_J, 72e-3, 72e-3 * 1e-6);
}

// Rays follow the beam's irradiance inside the field of view: for a 2-D Gaussian truncated
// at r0, E[r^2] = 2 s^2 (1 - (1 + a) e^-a) / (1 - e^-a), a = r0^2 / 2 s^2.
TEST(BeamSampler, AnglesFollowTheTruncatedGaussian) {
  const LidarModel lidar(table2_sensor());
  const BeamSampler beam(lidar, {0.0, 0.0, -1.0});
  const double s = 0.00011, a = 0.0002 * 0.0002 / (2 * s * s);
  const double expected = 2 * s * s * (1 - (1 + a) * std::exp(-a)) / (1 - std::exp(-a));
  double sum = 0, max_angle = 0;
  const int n = 200000;
  for (int i = 0; i < n; ++i) {
    RayRandom random(3, 0, i);
    const double u1 = random.uniform(), u2 = random.uniform();
    const Vec3 d = beam.direction(u1, u2);
    const double angle = std::acos(std::min(1.0, -d[2]));
    sum += angle * angle;
    max_angle = std::max(max_angle, angle);
  }
  EXPECT_NEAR(sum / n / expected, 1.0, 0.01);
  EXPECT_LE(max_angle, 0.0002 * (1 + 1e-6));
}

// A uniform beam of half-angle a = 2 sigma lights its cone evenly (RAMI-IV's lidar footprint): the
// part of the rays within an angle r of the axis is the area ratio (r / a)^2, where a Gaussian of
// the same sigma has 1 - exp(-r^2 / 2 sigma^2) (0.632 at r = a / sqrt 2, for the uniform 1/2); none
// beyond a. Inside a narrower field of view h, the rays fill the view evenly and f_fov = (h / a)^2.
TEST(BeamSampler, AUniformBeamLightsItsConeEvenly) {
  LidarSettings sensor = table2_sensor();
  sensor.beam_profile = "uniform";
  sensor.divergence_sigma_rad = 0.00005;  // a = 0.0001, inside the 0.0002 half field of view
  const LidarModel lidar(sensor);
  EXPECT_EQ(lidar.fov_fraction(), 1.0);
  const BeamSampler beam(lidar, {0.0, 0.0, -1.0});
  const double a = 0.0001;
  const int n = 200000;
  int inner = 0, quarter = 0;
  double max_angle = 0;
  for (int i = 0; i < n; ++i) {
    RayRandom random(3, 0, i);
    const double u1 = random.uniform(), u2 = random.uniform();
    const Vec3 d = beam.direction(u1, u2);
    const double angle = std::acos(std::min(1.0, -d[2]));
    inner += angle < a / std::sqrt(2.0);
    quarter += angle < 0.5 * a;
    max_angle = std::max(max_angle, angle);
  }
  // Binomial errors: sqrt(p (1 - p) / n) = 0.0011 and 0.0010; 5 of them.
  EXPECT_NEAR(double(inner) / n, 0.5, 0.0056);
  EXPECT_NEAR(double(quarter) / n, 0.25, 0.005);
  EXPECT_LE(max_angle, a * (1 + 1e-6));
  // The density the transport weighs the second path by: 1 / (pi a^2) inside (small angles),
  // none outside.
  EXPECT_NEAR(lidar.beam_density_sr(0.5 * a) * std::numbers::pi * a * a, 1.0, 1e-6);
  EXPECT_EQ(lidar.beam_density_sr(1.01 * a), 0.0);
  // A view narrower than the beam: the part of the beam it sees is the ratio of the solid angles.
  sensor.divergence_sigma_rad = 0.0002;  // a = 0.0004, twice the half field of view
  const LidarModel clipped(sensor);
  EXPECT_NEAR(clipped.fov_fraction(), 0.25, 1e-6);
  EXPECT_NEAR(clipped.beam_density_sr(0.0001) * std::numbers::pi * 0.0002 * 0.0002, 1.0, 1e-6);
}

TEST(RayRandom, DependsOnlyOnSeedShotAndRay) {
  RayRandom a(1, 2, 3), b(1, 2, 3), c(1, 2, 4), d(1, 3, 3), e(2, 2, 3);
  const double first = a.uniform();
  EXPECT_EQ(first, b.uniform());
  EXPECT_NE(first, c.uniform());
  EXPECT_NE(first, d.uniform());
  EXPECT_NE(first, e.uniform());
  double sum = 0;
  for (int i = 0; i < 100000; ++i) sum += a.uniform();
  EXPECT_NEAR(sum / 100000, 0.5, 0.005);
}

TEST(ShotTransport, SameBitsForAnyThreadCount) {
  const LidarModel lidar(table2_sensor());
  const PlaneTerrain plane({0.0, 0.0, 0.0, 20.0, 45.0});
  const LocalFrame frame({0.0, 0.0, 0.0});
  const RayDevice device;
  const Scene scene(device, build_ground_mesh(plane, frame, 200.0, 1.0e9));
  ShotGeometry geometry;
  geometry.sensor_m = {0.0, 0.0, 600000.0};
  geometry.axis = {0.0, 0.0, -1.0};
  geometry.range_m = 600000.0;
  SceneOptics optics;
  optics.soil_reflectance = {0.15, 0.3};
  TransportOptions options;
  options.rays = 20000;
  auto run = [&](int threads) {
    tbb::task_arena arena(threads);
    ShotWaveforms waveforms;
    arena.execute([&] { waveforms = simulate_shot(scene, lidar, geometry, optics, options, 11); });
    return waveforms;
  };
  const ShotWaveforms one = run(1), two = run(2);
  EXPECT_EQ(one.total_W, two.total_W);
  EXPECT_EQ(one.energy_J, two.energy_J);
  EXPECT_EQ(one.ray_queries, two.ray_queries);
  EXPECT_GE(one.ray_queries, 20000);
  // Another shot number is another sample.
  const ShotWaveforms other = simulate_shot(scene, lidar, geometry, optics, options, 12);
  EXPECT_NE(one.total_W, other.total_W);
}

// Crowns of one kind of foliage (0.45 both ways, bark 0.3, leaves 5 cm) over soil of 0.2.
struct OneKindScene : test_support::CrownScene {
  explicit OneKindScene(std::vector<Crown> crowns)
      : CrownScene(std::move(crowns), {{{0.45, 0.45}, {0.45, 0.45}, {0.3, 0.3}, 0.05}},
                   {0.2, 0.2}) {}
};

// Overlapping crowns add their foliage: two coincident crowns of density u scatter as one of 2u.
TEST(ShotTransport, OverlappingCrownsAddTheirFoliage) {
  const Crown crown{CrownShape::ellipsoid, {0.0, 0.0, 5.0}, 60.0, 8.0, 0.05};
  Crown dense = crown;
  dense.area_density_m2_m3 = 0.1;
  const OneKindScene two({crown, crown}), one({dense});
  const LidarModel lidar(table2_sensor());
  TransportOptions options;
  options.rays = 40000;
  options.max_order = 3;
  const ShotWaveforms a = simulate_shot(*two.scene, lidar, two.geometry, two.optics, options, 1);
  const ShotWaveforms b = simulate_shot(*one.scene, lidar, one.geometry, one.optics, options, 2);
  EXPECT_NEAR(a.canopy_energy_J[0] / b.canopy_energy_J[0], 1.0, 0.02);
  EXPECT_NEAR(a.ground_energy_J[0] / b.ground_energy_J[0], 1.0, 0.03);
}

// PHYSICS.md section 8: foliage never takes the place of a surface nearer along the ray. A wide
// crown centred on the ground (half of it below): the soil still returns rho_s e^(-G u 8), the
// light crossing the 8 m of foliage above it once (the hotspot).
TEST(ShotTransport, ACrownReachingBelowTheGroundKeepsTheGroundReturn) {
  const double u = 0.05;
  const OneKindScene scene({{CrownShape::ellipsoid, {0.0, 0.0, -8.0}, 300.0, 8.0, u}});
  const LidarModel lidar(table2_sensor());
  TransportOptions options;
  options.rays = 40000;
  options.max_order = 1;
  const ShotWaveforms w =
      simulate_shot(*scene.scene, lidar, scene.geometry, scene.optics, options, 3);
  const double f_fov = 1.0 - std::exp(-0.0004 * 0.0004 / (8.0 * 0.00011 * 0.00011));
  const double normalisation =
      32e-3 * 0.8 * 0.709 * f_fov / (std::numbers::pi * 600000.0 * 600000.0);
  EXPECT_NEAR(w.ground_energy_J[0] / normalisation / (0.2 * std::exp(-0.5 * u * 8.0)), 1.0, 0.02);
}

TEST(ShotTransport, SameBitsForAnyThreadCountInAForest) {
  const OneKindScene forest({{CrownShape::ellipsoid, {3.0, 0.0, 15.0}, 8.0, 8.0, 0.3},
                             {CrownShape::cone, {-6.0, 4.0, 12.0}, 5.0, 9.0, 0.4}});
  const LidarModel lidar(table2_sensor());
  TransportOptions options;
  options.rays = 12000;
  auto run = [&](int threads) {
    tbb::task_arena arena(threads);
    ShotWaveforms waveforms;
    arena.execute([&] {
      waveforms = simulate_shot(*forest.scene, lidar, forest.geometry, forest.optics, options, 5);
    });
    return waveforms;
  };
  const ShotWaveforms one = run(1), two = run(2);
  EXPECT_GT(one.canopy_energy_J[0], 0.0);
  EXPECT_EQ(one.total_W, two.total_W);
  EXPECT_EQ(one.canopy_W, two.canopy_W);
  // Quasi-random rays too: a ray's point depends on (seed, shot, ray) alone.
  options.quasi_random = true;
  const ShotWaveforms quasi_one = run(1), quasi_two = run(2);
  EXPECT_EQ(quasi_one.total_W, quasi_two.total_W);
  EXPECT_EQ(quasi_one.canopy_W, quasi_two.canopy_W);
  EXPECT_NE(quasi_one.total_W, one.total_W);
}

// What a ray meets first (element_met), against free paths worked by hand: a vertical ray down
// from 30 m over flat ground, through foliage of extinction G u = 0.5 * 0.4 = 0.2 per metre.
// Optical depth tau is reached 20 + tau / 0.2 m along the ray from the foliage's top at 10 m
// (height); the ground lies 30 m along it.
// Level ground at z = 0, 200 m square about the origin.
GroundMesh square_ground() {
  GroundMesh ground;
  ground.vertices_m = {-100, -100, 0, 100, -100, 0, 100, 100, 0, -100, 100, 0};
  ground.triangles = {0, 1, 2, 0, 2, 3};
  return ground;
}

struct VerticalRay {
  explicit VerticalRay(const Vegetation& vegetation)
      : scene(std::make_unique<Scene>(device, square_ground(), vegetation)) {}
  ElementMet meet(std::optional<double> depth, double limit_m = far_m) {
    auto uniform = [this] {
      ++draws;
      return 0.5;
    };
    return element_met(*scene, {0.0, 0.0, 30.0}, {0.0, 0.0, -1.0}, limit_m, 0.0, depth, spans,
                       projection, uniform);
  }
  RayDevice device;
  std::unique_ptr<Scene> scene;
  std::vector<VolumeSpan> spans;
  const std::vector<double> projection{0.5};
  int draws = 0;  // uniform numbers taken: one to choose the foliage of each leaf met
};

TEST(ElementMet, ALeafWhereTheFreePathEndsBeforeTheGround) {
  Vegetation layer;
  layer.layer = TurbidLayer{0.0, 0.0, 0.0, 10.0, 0.4, 0};
  VerticalRay ray(layer);
  const ElementMet met = ray.meet(1.0);
  ASSERT_TRUE(met.leaf.has_value());
  EXPECT_NEAR(met.leaf->distance_m, 20.0 + 1.0 / 0.2, 1e-12);
  EXPECT_EQ(met.leaf->crown, -1);
  EXPECT_EQ(met.surface.kind, SurfaceKind::none);  // searched only as far as the leaf
  EXPECT_EQ(ray.draws, 1);
}

TEST(ElementMet, TheGroundWhereTheFreePathWouldEndBeyondIt) {
  Vegetation layer;
  layer.layer = TurbidLayer{0.0, 0.0, 0.0, 10.0, 0.4, 0};
  VerticalRay ray(layer);
  const ElementMet met = ray.meet(2.5);  // the layer holds 2.0 of optical depth
  EXPECT_FALSE(met.leaf.has_value());
  EXPECT_EQ(met.surface.kind, SurfaceKind::ground);
  EXPECT_NEAR(met.surface.distance_m, 30.0, 1e-5);
  EXPECT_NEAR(met.surface.normal[2], 1.0, 1e-12);
  EXPECT_EQ(ray.draws, 0);
}

// A crown centred on the ground: its foliage goes on below the ground, where the free path of
// depth 3 would end (35 m), but the ground at 30 m comes first. Depth 1 ends at 25 m, above it.
TEST(ElementMet, FoliageBelowTheGroundIsNeverMet) {
  Vegetation crown;
  crown.crowns = {{CrownShape::ellipsoid, {0.0, 0.0, -10.0}, 50.0, 10.0, 0.4}};
  VerticalRay ray(crown);
  const ElementMet below = ray.meet(3.0);
  EXPECT_FALSE(below.leaf.has_value());
  EXPECT_EQ(below.surface.kind, SurfaceKind::ground);
  EXPECT_NEAR(below.surface.distance_m, 30.0, 1e-5);
  const ElementMet above = ray.meet(1.0);
  ASSERT_TRUE(above.leaf.has_value());
  EXPECT_NEAR(above.leaf->distance_m, 25.0, 1e-12);
  EXPECT_EQ(above.leaf->crown, 0);
  EXPECT_EQ(ray.draws, 1);
}

// Without foliage only the surfaces are searched; nothing is met short of the limit.
TEST(ElementMet, OnlyTheSurfacesWithoutFoliageAndNothingBeyondTheLimit) {
  VerticalRay bare({});
  const ElementMet ground = bare.meet(std::nullopt);
  EXPECT_EQ(ground.surface.kind, SurfaceKind::ground);
  EXPECT_EQ(ground.ray_queries, 1);
  Vegetation layer;
  layer.layer = TurbidLayer{0.0, 0.0, 0.0, 10.0, 0.4, 0};
  VerticalRay ray(layer);
  const ElementMet met = ray.meet(2.5, 28.0);
  EXPECT_FALSE(met.leaf.has_value());
  EXPECT_EQ(met.surface.kind, SurfaceKind::none);
  EXPECT_EQ(met.ray_queries, 2);
}

// Spans searched for a free path stop short of crowns beyond it: through a forest of 400 crowns
// of two densities, rays in every direction find the free path, and the foliage met there, that
// every span along them gives, while fewer crowns are visited in all.
TEST(ElementMet, SpansCutAtTheFreePathGiveTheFreePathOfEverySpan) {
  RayDevice device;
  Vegetation forest;
  RayRandom place(5, 0, 0);
  for (int k = 0; k < 400; ++k)
    forest.crowns.push_back(
        {k % 3 ? CrownShape::ellipsoid : CrownShape::cone,
         {100.0 * place.uniform() - 50.0, 100.0 * place.uniform() - 50.0, 4.0 * place.uniform()},
         1.0 + 3.0 * place.uniform(),
         2.0 + 4.0 * place.uniform(),
         k % 2 ? 0.3 : 1.2,
         k % 2});
  const Scene scene(device, square_ground(), forest);
  const std::vector<double> projection{0.5, 0.8};
  std::vector<VolumeSpan> every, cut;
  std::size_t spans_every = 0, spans_cut = 0;
  int leaves = 0;
  RayRandom random(6, 0, 0);
  for (int ray = 0; ray < 4000; ++ray) {
    const Vec3 origin{60.0 * random.uniform() - 30.0, 60.0 * random.uniform() - 30.0,
                      20.0 * random.uniform()};
    const double cos_zenith = 2.0 * random.uniform() - 1.0, azimuth = 6.283 * random.uniform();
    const double sin_zenith = std::sqrt(1.0 - cos_zenith * cos_zenith);
    const Vec3 direction{sin_zenith * std::cos(azimuth), sin_zenith * std::sin(azimuth),
                         cos_zenith};
    const double depth = -std::log1p(-random.uniform()), pick = random.uniform();
    scene.volume_spans(origin, direction, far_m, every);
    scene.volume_spans(origin, direction, far_m, cut, depth, projection);
    spans_every += every.size();
    spans_cut += cut.size();
    const auto a = free_path_depth(every, projection, depth);
    const auto b = free_path_depth(cut, projection, depth);
    ASSERT_EQ(a.has_value(), b.has_value()) << "ray " << ray;
    if (!a) continue;
    ++leaves;
    EXPECT_EQ(a->distance_m, b->distance_m) << "ray " << ray;
    EXPECT_EQ(a->extinction_per_m, b->extinction_per_m) << "ray " << ray;
    auto same = [pick] { return pick; };
    EXPECT_EQ(foliage_met(every, projection, *a, same).crown,
              foliage_met(cut, projection, *b, same).crown)
        << "ray " << ray;
  }
  EXPECT_GT(leaves, 1000);
  EXPECT_LT(spans_cut, spans_every * 9 / 10);
}

}  // namespace
}  // namespace glaswave
