// `brf`'s sunlight through the atmosphere's layers (issue 40) against numbers worked here without
// the transport: energy conservation under a conservative layer, Beer-Lambert for the direct
// light, the single scattering of a thin Henyey-Greenstein layer (its diffuse light at the
// scene's top and its reflectance at the layers' top) by quadrature, and a Lambertian ground
// under an absorbing layer (its exp(-tau / mu) down and 2 E3(tau) up).
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <numbers>

#include "pipeline/transport/atmosphere.hpp"
#include "pipeline/transport/brf_transport.hpp"
#include "terrain/ground_mesh.hpp"
#include "terrain/terrain.hpp"
#include "tests/pipeline/transport/transport_test_support.hpp"

namespace glaswave {
namespace {

using test_support::uniform_layer;

constexpr double pi = std::numbers::pi;
constexpr double deg = pi / 180.0;

Vec3 toward(double zenith_deg, double azimuth_deg) {
  return {std::sin(zenith_deg * deg) * std::sin(azimuth_deg * deg),
          std::sin(zenith_deg * deg) * std::cos(azimuth_deg * deg), std::cos(zenith_deg * deg)};
}

AtmospherePhase hg(double g) { return {AtmospherePhase::Kind::henyey_greenstein, g, 0.0, 1.0}; }
AtmospherePhase rayleigh() { return {}; }

// Level ground (and optional crowns) over a periodic tile of 60 m, under `layers`; the ground
// and leaves the same in every band.
struct SkyScene {
  SkyScene(std::size_t bands, double soil, double rho, double tau, std::vector<Crown> crowns = {}) {
    vegetation.crowns = std::move(crowns);
    scene =
        std::make_unique<Scene>(device, build_ground_mesh(plane, frame, 40.0, 1.0e9), vegetation);
    optics.soil_reflectance.assign(bands, soil);
    optics.foliage.push_back({std::vector<double>(bands, rho), std::vector<double>(bands, tau),
                              std::vector<double>(bands, soil), &angles, 0.05});
    tile.half_size_m = 30.0;
  }
  BrfResult run(const std::vector<AtmosphereLayer>& layers, const Vec3& toward_sun,
                std::vector<Vec3> views, std::int64_t photons) const {
    BrfOptions options;
    options.sun_direction = -1.0 * toward_sun;
    options.views = std::move(views);
    options.photons = photons;
    options.seed = 5;
    options.image_pixels = 4;
    options.atmosphere = AtmosphereSettings{"", layers};
    return simulate_brf(*scene, optics, tile, options);
  }

  PlaneTerrain plane{{0.0, 0.0, 0.0, 0.0, 0.0}};
  LocalFrame frame{{0.0, 0.0, 0.0}};
  RayDevice device;
  Vegetation vegetation;
  std::unique_ptr<Scene> scene;
  LeafAngles angles{LeafAngleDistribution::spherical, 0.0};
  SceneOptics optics;
  BrfTile tile;
};

std::vector<Crown> four_crowns() {
  std::vector<Crown> crowns;
  for (int k = 0; k < 4; ++k) {
    Crown crown;
    crown.base_m = {-30.0 + 20.0 * k, 29.0 - 19.0 * k, 3.0};
    crown.radius_m = 6.0;
    crown.half_height_m = 5.0;
    crown.area_density_m2_m3 = 1.0;
    crowns.push_back(crown);
  }
  return crowns;
}

// Molecules, a boundary-layer aerosol and a stratus, all with single-scattering albedo `omega`.
std::vector<AtmosphereLayer> cloudy(double omega) {
  return {uniform_layer(0.0, 8000.0, 0.1, {omega}, rayleigh()),
          uniform_layer(0.0, 2000.0, 0.2, {omega}, hg(0.7)),
          uniform_layer(500.0, 1500.0, 2.0, {omega}, hg(0.85))};
}

// The test: a conservative atmosphere (albedo 1, the stratus of tau 2 within it) over a
// white scene that absorbs nothing (soil 1, leaves rho + tau = 1, crowns across the tile's
// sides): all the sunlight leaves through the top of the layers, to 0.5 %, after bouncing
// between the cloud and the scene (the light reaching the scene in all is more than the sun's).
TEST(BrfAtmosphere, ConservativeLayersOverAWhiteSceneReflectEverything) {
  const SkyScene white(1, 1.0, 0.6, 0.4, four_crowns());
  const BrfResult r = white.run(cloudy(1.0), toward(35.0, 70.0), {toward(0, 0)}, 4000);
  ASSERT_TRUE(r.sky);
  RecordProperty("toa_albedo", std::to_string(r.sky->albedo[0]));
  RecordProperty("downward", std::to_string(r.sky->downward[0]));
  EXPECT_NEAR(r.sky->albedo[0], 1.0, 0.005);
  EXPECT_NEAR(r.sky->absorbed[0], 0.0, 1e-12);
  EXPECT_GT(r.sky->downward[0], 1.05);  // the cloud sends the scene's light back down
  EXPECT_NEAR(r.albedo[0], 1.0, 0.005);
}

// With absorption everywhere (the layers' albedo 0.9, leaves 0.45 / 0.3, soil 0.2) the sunlight
// is split between the top of the layers and the layers', canopy's and soil's absorption; each
// share counts, and they sum to 1 within three standard errors (Russian roulette's), as the
// scene's own light does at its top.
TEST(BrfAtmosphere, AbsorbingLayersAndSceneCloseTheEnergy) {
  const SkyScene scene(1, 0.2, 0.45, 0.3, four_crowns());
  const BrfResult r = scene.run(cloudy(0.9), toward(35.0, 70.0), {toward(0, 0)}, 4000);
  ASSERT_TRUE(r.sky);
  const BrfSky& sky = *r.sky;
  RecordProperty("toa_albedo", std::to_string(sky.albedo[0]));
  RecordProperty("layers_absorbed", std::to_string(sky.absorbed[0]));
  RecordProperty("canopy_absorbed", std::to_string(r.absorbed[0] * sky.downward[0]));
  RecordProperty("closure", std::to_string(sky.closure[0]));
  EXPECT_GT(sky.albedo[0], 0.1);
  EXPECT_GT(sky.absorbed[0], 0.1);
  EXPECT_GT(r.absorbed[0] * sky.downward[0], 0.03);  // the canopy's, of the sun's light
  EXPECT_NEAR(sky.closure[0], 1.0, 3.0 * sky.closure_stderr[0] + 1e-12);
  EXPECT_NEAR(r.closure[0], 1.0, 3.0 * r.closure_stderr[0] + 1e-12);
  EXPECT_LT(sky.closure_stderr[0], 0.01);
}

// The direct sunlight at the scene's top is Beer-Lambert's exp(-tau / mu_sun) of the column
// above it (overlapping layers of 0.1 and 0.3, the molecules' cut at the scene's top), within
// three standard errors of its binomial count. The scene's top is 1 m above its highest point.
TEST(BrfAtmosphere, DirectLightIsBeerLambert) {
  const SkyScene black(1, 0.0, 0.0, 0.0);
  const double mu = std::cos(50.0 * deg);
  const BrfResult r = black.run({uniform_layer(-500.0, 8000.0, 0.1, {1.0}, rayleigh()),
                                 uniform_layer(1000.0, 3000.0, 0.3, {0.95}, hg(0.75))},
                                toward(50.0, 200.0), {toward(0, 0)}, 20000);
  const double floor_m = black.scene->top_m() + 1.0;
  const double expected = std::exp(-(0.1 * (8000.0 - floor_m) / 8500.0 + 0.3) / mu);
  RecordProperty("direct", std::to_string(r.sky->direct[0]));
  RecordProperty("expected", std::to_string(expected));
  EXPECT_LT(r.sky->direct_stderr[0], 0.005);
  EXPECT_NEAR(r.sky->direct[0], expected, 3.0 * r.sky->direct_stderr[0]);
}

// Single scattering of a homogeneous Henyey-Greenstein layer of optical depth tau, albedo omega,
// lit at mu0 (scattering angle Theta from the sun's direction):
// - the diffuse light reaching its base, per unit of the sunlight at its top,
//     t = (omega / mu0) int_down dOmega p(Theta) int_0^tau e^(-t / mu0) e^(-(tau - t) / mu) dt,
//   the inner integral e^(-tau / mu) (1 - e^(-a tau)) / a, a = 1 / mu0 - 1 / mu;
// - its reflectance at the top toward mu_v, pi L / (E mu0) =
//     omega pi p(Theta) (1 - e^(-tau (1 / mu0 + 1 / mu_v))) / (mu0 + mu_v).
// Band 1 scatters a hundredth of what band 0 does: its weight drops a hundredfold at each
// scattering (the free paths follow band 0), so its light is single scattering to 0.2 %.
double hg_phase(double g, double c) {
  const double d = 1.0 + g * g - 2.0 * g * c;
  return (1.0 - g * g) / (4.0 * pi * d * std::sqrt(d));
}

double diffuse_single(double tau, double g, double mu0) {
  const int nmu = 4000, nphi = 720;
  const double s0 = std::sqrt(1.0 - mu0 * mu0);
  double sum = 0.0;
  for (int i = 0; i < nmu; ++i) {
    const double mu = (i + 0.5) / nmu, s = std::sqrt(1.0 - mu * mu);
    const double a = 1.0 / mu0 - 1.0 / mu;  // the inner integral, written to stay finite
    const double depth = std::abs(a * tau) < 1e-9
                             ? tau * std::exp(-tau / mu)
                             : (std::exp(-tau / mu) - std::exp(-tau / mu0)) / a;
    for (int j = 0; j < nphi; ++j) {
      const double phi = 2.0 * pi * (j + 0.5) / nphi;
      sum += hg_phase(g, mu * mu0 + s * s0 * std::cos(phi)) * depth;
    }
  }
  return sum * (1.0 / nmu) * (2.0 * pi / nphi) / mu0;
}

TEST(BrfAtmosphere, ThinLayerSingleScatteringMatchesQuadrature) {
  const double tau = 0.2, g = 0.7, omega = 0.01, mu0 = std::cos(40.0 * deg);
  const SkyScene black(2, 0.0, 0.0, 0.0);
  const Vec3 sun = toward(40.0, 0.0);
  const std::vector<Vec3> views = {toward(0.0, 0.0), toward(40.0, 0.0), toward(30.0, 180.0)};
  const BrfResult r =
      black.run({uniform_layer(2000.0, 3000.0, tau, {1.0, omega}, hg(g))}, sun, views, 100000);
  const double expected = omega * diffuse_single(tau, g, mu0);
  // Less than all the light the layer scatters, more than the half of it a forward peak sends on.
  EXPECT_LT(expected / omega, -std::expm1(-tau / mu0));
  EXPECT_GT(expected / omega, -0.5 * std::expm1(-tau / mu0));
  RecordProperty("diffuse", std::to_string(r.sky->diffuse[1]));
  RecordProperty("expected", std::to_string(expected));
  EXPECT_LT(r.sky->diffuse_stderr[1], 0.01 * expected);
  EXPECT_NEAR(r.sky->diffuse[1], expected, 3.0 * r.sky->diffuse_stderr[1] + 0.003 * expected);
  for (std::size_t v = 0; v < views.size(); ++v) {
    const double mu_v = views[v][2];
    const double cos_theta = dot(-1.0 * sun, views[v]);
    const double reflectance = omega * pi * hg_phase(g, cos_theta) *
                               -std::expm1(-tau * (1.0 / mu0 + 1.0 / mu_v)) / (mu0 + mu_v);
    RecordProperty("toa_brf_" + std::to_string(v), std::to_string(r.sky->brf[1][v]));
    RecordProperty("toa_expected_" + std::to_string(v), std::to_string(reflectance));
    EXPECT_NEAR(r.sky->brf[1][v], reflectance, 3.0 * r.sky->brf_stderr[1][v] + 0.003 * reflectance);
  }
}

// A Lambertian ground of reflectance 0.3 under a layer that only absorbs (tau 0.5): the sun
// reaches it by exp(-tau / mu0); its radiance leaves the layer toward mu_v by exp(-tau / mu_v)
// and its flux by 2 E3(tau) (E3 the exponential integral, by quadrature here), so the top's
// albedo is 0.3 exp(-tau / mu0) 2 E3(tau). At the scene's top, under any light, the ground's
// reflectance factor is 0.3 in every view and its albedo 0.3.
TEST(BrfAtmosphere, LambertianGroundUnderAnAbsorbingLayer) {
  const double tau = 0.5, rho = 0.3, mu0 = std::cos(30.0 * deg);
  const SkyScene ground(1, rho, 0.0, 0.0);
  const std::vector<Vec3> views = {toward(0.0, 0.0), toward(50.0, 120.0)};
  const BrfResult r = ground.run({uniform_layer(100.0, 4100.0, tau, {0.0}, rayleigh())},
                                 toward(30.0, 10.0), views, 20000);
  double e3 = 0.0;  // E3(tau) = int_0^1 mu e^(-tau / mu) dmu
  const int n = 100000;
  for (int i = 0; i < n; ++i) {
    const double mu = (i + 0.5) / n;
    e3 += mu * std::exp(-tau / mu) / n;
  }
  const double down = std::exp(-tau / mu0);
  EXPECT_NEAR(r.sky->direct[0], down, 1e-12);
  EXPECT_NEAR(r.sky->diffuse[0], 0.0, 1e-12);
  for (std::size_t v = 0; v < views.size(); ++v) {
    EXPECT_NEAR(r.brf[0][v], rho, 1e-6);
    EXPECT_NEAR(r.sky->brf[0][v], rho * down * std::exp(-tau / views[v][2]), 1e-6);
  }
  const double albedo = rho * down * 2.0 * e3;
  RecordProperty("toa_albedo", std::to_string(r.sky->albedo[0]));
  RecordProperty("expected", std::to_string(albedo));
  EXPECT_NEAR(r.sky->albedo[0], albedo, 3.0 * r.sky->albedo_stderr[0]);
  EXPECT_NEAR(r.albedo[0], rho, 3.0 * r.albedo_stderr[0] + 1e-12);
  double mean = 0.0;
  for (double value : r.image[0]) mean += value / r.image[0].size();
  EXPECT_NEAR(mean, rho, 1e-6);
}

// Through the layers too, the same photons give the same bits on one thread and on two.
TEST(BrfAtmosphere, SameBitsForAnyThreadCount) {
  const SkyScene scene(1, 0.2, 0.45, 0.3, four_crowns());
  auto run_on = [&](int threads) {
    tbb::task_arena arena(threads);
    BrfResult r;
    arena.execute(
        [&] { r = scene.run(cloudy(0.95), toward(30.0, 0.0), {toward(10.0, 90.0)}, 3000); });
    return r;
  };
  const BrfResult one = run_on(1), two = run_on(2);
  EXPECT_EQ(one.brf, two.brf);
  EXPECT_EQ(one.sky->brf, two.sky->brf);
  EXPECT_EQ(one.sky->albedo, two.sky->albedo);
  EXPECT_EQ(one.image, two.image);
}

// A sloping periodic tile cannot lie under level layers: refused, not traced.
TEST(BrfAtmosphere, SlopingTileIsRefused) {
  SkyScene scene(1, 0.2, 0.0, 0.0);
  scene.tile.ground_slope_x = 0.1;
  EXPECT_THROW(scene.run(cloudy(1.0), toward(30.0, 0.0), {toward(0, 0)}, 10),
               std::invalid_argument);
}

}  // namespace
}  // namespace glaswave
