// The sun's transport of `brf` (FLIGHT's solar mode) against answers known independently of it:
// a Lambertian plane, energy conservation, reciprocity, and the single scattering of a turbid
// layer in the hotspot (PHYSICS.md sections 3 and 4).
#include "pipeline/transport/brf_transport.hpp"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <cstring>
#include <numbers>

#include "terrain/ground_mesh.hpp"
#include "terrain/terrain.hpp"

namespace glaswave {
namespace {

constexpr double deg = std::numbers::pi / 180.0;

Vec3 toward(double zenith_deg, double azimuth_deg) {
  return {std::sin(zenith_deg * deg) * std::sin(azimuth_deg * deg),
          std::sin(zenith_deg * deg) * std::cos(azimuth_deg * deg), std::cos(zenith_deg * deg)};
}

// Level ground under an optional homogeneous layer of spherical leaves (20 m deep) and crowns,
// lit over a periodic tile of 60 m; one band.
struct SunScene {
  SunScene(double soil, double pai, double rho, double tau, double leaf_size_m,
           std::vector<Crown> crowns = {}) {
    if (pai > 0.0) {
      TurbidLayer layer;
      layer.bottom_m = 2.0;
      layer.top_m = 22.0;
      layer.area_density_m2_m3 = pai / 20.0;
      vegetation.layer = layer;
    }
    vegetation.crowns = std::move(crowns);
    scene =
        std::make_unique<Scene>(device, build_ground_mesh(plane, frame, 40.0, 1.0e9), vegetation);
    optics.soil_reflectance = {soil};
    optics.foliage.push_back({{rho}, {tau}, {soil}, &angles, leaf_size_m});
    tile.half_size_m = 30.0;
  }

  BrfResult run(const Vec3& toward_sun, std::vector<Vec3> views, std::int64_t photons,
                int max_order) const {
    BrfOptions options;
    options.sun_direction = -1.0 * toward_sun;
    options.views = std::move(views);
    options.photons = photons;
    options.max_order = max_order;
    options.seed = 3;
    options.image_pixels = 6;
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

// Bare Lambertian ground: every photon scores rho toward every view, so the BRF is rho with no
// spread, and a reflectance of rho is all that leaves. To 1e-6: the ground follows the ellipsoid
// (its normal tilts by up to 30 m / 6371 km = 5e-6 rad at the tile's edge) through Embree's
// float normals.
TEST(BrfTransport, LambertianGroundIsItsReflectanceInEveryView) {
  const SunScene bare(0.3, 0.0, 0.0, 0.0, 0.0);
  const BrfResult r = bare.run(toward(40.0, 10.0), {toward(0, 0), toward(60, 200)}, 2000, 5);
  ASSERT_EQ(r.brf.size(), 1u);
  for (std::size_t v = 0; v < 2; ++v) {
    EXPECT_NEAR(r.brf[0][v], 0.3, 1e-6);
    EXPECT_NEAR(r.brf_stderr[0][v], 0.0, 1e-6);
  }
  EXPECT_NEAR(r.albedo[0], 0.3, 1e-12);
  // The nadir image averages to the nadir BRF (every pixel 0.3 within its photon count's noise).
  double mean = 0.0;
  for (double value : r.image[0]) mean += value / r.image[0].size();
  EXPECT_NEAR(mean, 0.3, 1e-6);
}

// PHYSICS.md section 4: with leaves that absorb nothing (rho + tau = 1) over white soil, and the
// tile periodic, everything that enters leaves through the top: the albedo is 1 (to 0.5 %).
// Crowns straddling the tile's sides are crossed by wrapped paths too.
TEST(BrfTransport, NonAbsorbingSceneHasAlbedoOne) {
  std::vector<Crown> crowns;
  for (int k = 0; k < 4; ++k) {
    Crown crown;
    crown.base_m = {-30.0 + 20.0 * k, 29.0 - 19.0 * k, 3.0};
    crown.radius_m = 6.0;
    crown.half_height_m = 5.0;
    crown.area_density_m2_m3 = 1.0;
    crowns.push_back(crown);
  }
  const SunScene white(1.0, 2.0, 0.6, 0.4, 0.05, crowns);
  const BrfResult r = white.run(toward(35.0, 70.0), {toward(0, 0)}, 4000, 1000);
  RecordProperty("albedo", std::to_string(r.albedo[0]));
  EXPECT_NEAR(r.albedo[0], 1.0, 0.005);
}

// Helmholtz reciprocity: the BRF with sun and view exchanged is the same, within three of the
// two estimates' combined standard errors, all orders included.
TEST(BrfTransport, ReciprocityOfSunAndView) {
  const SunScene layer(0.2, 2.0, 0.45, 0.3, 0.05);
  const Vec3 a = toward(20.0, 0.0), b = toward(55.0, 130.0);
  const BrfResult forward = layer.run(a, {b}, 40000, 8);
  const BrfResult backward = layer.run(b, {a}, 40000, 8);
  const double sigma = std::hypot(forward.brf_stderr[0][0], backward.brf_stderr[0][0]);
  EXPECT_GT(forward.brf[0][0], 0.05);
  EXPECT_LT(sigma, 0.02 * forward.brf[0][0]);
  RecordProperty("forward", std::to_string(forward.brf[0][0]));
  RecordProperty("backward", std::to_string(backward.brf[0][0]));
  RecordProperty("sigma", std::to_string(sigma));
  EXPECT_NEAR(forward.brf[0][0], backward.brf[0][0], 3.0 * sigma);
}

// Single scattering of a homogeneous layer (LAI L, spherical leaves, G = 1/2) over black soil,
// seen in the retro direction at sun zenith theta (mu = cos theta). A photon collides at
// cumulative leaf area l below the top with density (G/mu) e^(-G l / mu); the leaf it meets,
// drawn by |n.Omega|, returns rho |n.Omega| toward the sun (mean 2 rho / 3), and the BRF is
// that over mu. The way out runs back down the way in: with finite leaves it finds the same
// gaps (transmittance 1), so BRF = (2 rho / (3 mu)) (1 - e^(-L / (2 mu))); with point leaves
// it is attenuated again, e^(-G l / mu), so BRF = (rho / (3 mu)) (1 - e^(-L / mu)). At nadir
// these are PHYSICS.md section 3's (2 rho/3)(1 - e^(-L/2)) and (rho/3)(1 - e^(-L)). To 2 %.
TEST(BrfTransport, TurbidLayerSingleScatteringInTheHotspotMatchesTheClosedForm) {
  const double L = 3.0, rho = 0.45, tau = 0.3, mu = std::cos(30.0 * deg);
  const Vec3 sun = toward(30.0, 45.0);
  const double hotspot = 2.0 * rho / (3.0 * mu) * (1.0 - std::exp(-L / (2.0 * mu)));
  const double point = rho / (3.0 * mu) * (1.0 - std::exp(-L / mu));
  EXPECT_NEAR(hotspot, 0.2851, 5e-4);  // the numbers themselves, worked by hand
  EXPECT_NEAR(point, 0.1679, 5e-4);
  const BrfResult finite = SunScene(0.0, L, rho, tau, 0.05).run(sun, {sun}, 40000, 1);
  const BrfResult points = SunScene(0.0, L, rho, tau, 0.0).run(sun, {sun}, 40000, 1);
  RecordProperty("finite", std::to_string(finite.brf[0][0]));
  RecordProperty("points", std::to_string(points.brf[0][0]));
  EXPECT_NEAR(finite.brf[0][0] / hotspot, 1.0, 0.02);
  EXPECT_NEAR(points.brf[0][0] / point, 1.0, 0.02);
}

// The same photons give the same bits on one thread and on two.
TEST(BrfTransport, SameBitsForAnyThreadCount) {
  const SunScene layer(0.2, 2.0, 0.45, 0.3, 0.05);
  auto run_on = [&](int threads) {
    tbb::task_arena arena(threads);
    BrfResult r;
    arena.execute([&] { r = layer.run(toward(30.0, 0.0), {toward(10.0, 90.0)}, 5000, 8); });
    return r;
  };
  const BrfResult one = run_on(1), two = run_on(2);
  EXPECT_EQ(std::memcmp(&one.brf[0][0], &two.brf[0][0], sizeof(double)), 0);
  EXPECT_EQ(std::memcmp(&one.brf_stderr[0][0], &two.brf_stderr[0][0], sizeof(double)), 0);
  EXPECT_EQ(std::memcmp(&one.albedo[0], &two.albedo[0], sizeof(double)), 0);
  EXPECT_EQ(one.image, two.image);
}

}  // namespace
}  // namespace glaswave
