// Leaf facets in both transports against numbers known without them: a slab of many small random
// facets of spherical orientation is the turbid layer of PHYSICS.md section 3 (its single
// scattering tends to the hotspot column as the facets shrink: more facets under the beam, less
// spread of one slab's gaps about their mean), and `brf` over non-absorbing facets and white soil
// loses nothing (section 4).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <memory>
#include <numbers>
#include <random>
#include <vector>

#include "pipeline/scene/facet_model.hpp"
#include "pipeline/transport/brf_transport.hpp"
#include "pipeline/transport/shot_transport.hpp"
#include "tests/pipeline/transport/transport_test_support.hpp"

namespace glaswave {
namespace {

// A slab (realisation `seed`) `half_m` wide each way from the origin, between bottom_m and bottom_m
// + 10 m, of equilateral leaf triangles of side `side_m` (material 0) whose centres are uniform in
// it and whose normals are uniform on the sphere, as many as make a one-sided leaf area index L;
// and, when `trunks`, a few vertical wood panels (material 1) through it.
std::shared_ptr<const FacetModel> facet_slab(double L, double side_m, double half_m,
                                             double bottom_m, std::uint64_t seed,
                                             bool trunks = false) {
  std::mt19937_64 bits(seed);
  auto uniform = [&bits] { return static_cast<double>(bits() >> 11) * 0x1.0p-53; };
  const double leaf_m2 = std::sqrt(3.0) / 4.0 * side_m * side_m;
  const auto leaves = static_cast<std::size_t>(std::llround(L * 4.0 * half_m * half_m / leaf_m2));
  FacetMesh mesh;
  mesh.material_names = {"leaf", "wood"};
  const double circumradius = side_m / std::sqrt(3.0);
  for (std::size_t k = 0; k < leaves; ++k) {
    const Vec3 centre{(2.0 * uniform() - 1.0) * half_m, (2.0 * uniform() - 1.0) * half_m,
                      bottom_m + 10.0 * uniform()};
    const double cos_t = 2.0 * uniform() - 1.0, phi = 2.0 * std::numbers::pi * uniform();
    const double sin_t = std::sqrt(1.0 - cos_t * cos_t);
    const Vec3 n{sin_t * std::cos(phi), sin_t * std::sin(phi), cos_t};
    const Vec3 helper = std::abs(n[2]) < 0.9 ? Vec3{0.0, 0.0, 1.0} : Vec3{1.0, 0.0, 0.0};
    const Vec3 u = normalized(cross(n, helper)), v = cross(n, u);
    const double spin = 2.0 * std::numbers::pi * uniform();
    const auto first = static_cast<std::uint32_t>(mesh.vertices_m.size() / 3);
    for (int corner = 0; corner < 3; ++corner) {
      const double a = spin + 2.0 * std::numbers::pi * corner / 3.0;
      const Vec3 p = centre + circumradius * (std::cos(a) * u + std::sin(a) * v);
      for (int i = 0; i < 3; ++i) mesh.vertices_m.push_back(static_cast<float>(p[i]));
    }
    mesh.triangles.insert(mesh.triangles.end(), {first, first + 1, first + 2});
    mesh.materials.push_back(0);
  }
  if (trunks)
    for (double x = -half_m + 5.0; x < half_m; x += 10.0) {
      const auto first = static_cast<std::uint32_t>(mesh.vertices_m.size() / 3);
      const float y0 = static_cast<float>(-half_m), y1 = static_cast<float>(half_m);
      const auto xf = static_cast<float>(x), z0 = static_cast<float>(bottom_m),
                 z1 = static_cast<float>(bottom_m + 10.0);
      mesh.vertices_m.insert(mesh.vertices_m.end(),
                             {xf, y0, z0, xf, y1, z0, xf, y1, z1, xf, y0, z1});
      mesh.triangles.insert(mesh.triangles.end(),
                            {first, first + 1, first + 2, first, first + 2, first + 3});
      mesh.materials.insert(mesh.materials.end(), {1, 1});
    }
  std::vector<int> materials(mesh.materials.begin(), mesh.materials.end());
  return std::make_shared<const FacetModel>(std::move(mesh), std::move(materials));
}

// A nadir beam of 10 urad from 600 km (sigma 6 m on the ground) seen through a 40 urad field of
// view (12 m), one band of 1 mJ: narrow, so that a slab 40 m across is wider than the beam.
LidarSettings narrow_sensor() {
  LidarSettings sensor;
  sensor.pulse_sigma_ns = 5.0;
  sensor.divergence_sigma_rad = 1e-5;
  sensor.ifov_rad = 4e-5;
  sensor.telescope_area_m2 = 0.709;
  sensor.bin_ns = 1.0;
  sensor.bins = 544;
  sensor.bands = {{1064.0, 1.0, 1.0, "1064"}};
  return sensor;
}

struct SlabResult {
  double canopy, ground;
};

// Single scattering of the slab (rho 0.45, tau 0.45, soil 0.3), normalised as section 3 says.
SlabResult slab_single_scattering(double side_m, std::int64_t rays, std::uint64_t seed) {
  test_support::CrownScene base({}, {{{0.45}, {0.45}, {0.45}, 0.0}}, {0.3});
  Vegetation vegetation;
  vegetation.facets = {{facet_slab(3.0, side_m, 20.0, 1.0, seed), {0.0, 0.0, 0.0}, 0.0, 1.0}};
  vegetation.leaf_materials = {1, 0};
  base.optics.foliage.push_back(base.optics.foliage.front());
  const Scene scene(base.device, build_ground_mesh(base.plane, base.frame, 150.0, 1.0e9),
                    vegetation);
  const LidarModel lidar(narrow_sensor());
  TransportOptions options;
  options.rays = rays;
  options.max_order = 1;
  options.seed = 5;
  const ShotWaveforms w = simulate_shot(scene, lidar, base.geometry, base.optics, options, 0);
  const double f_fov = 1.0 - std::exp(-4e-5 * 4e-5 / (8.0 * 1e-5 * 1e-5));
  const double unit_J = 1e-3 * 0.709 * f_fov / (std::numbers::pi * 600000.0 * 600000.0);
  return {w.canopy_energy_J[0] / unit_J, w.ground_energy_J[0] / unit_J};
}

// PHYSICS.md section 3's hotspot column for L = 3, rho 0.45, soil 0.3 at nadir: the canopy
// (2 rho / 3)(1 - e^(-L/2)) = 0.2331 and the ground rho_s e^(-L/2) = 0.06694. A facet's way back
// to the sensor is the very path that found it (the hotspot, with no leaf size to give), and a
// random slab of facets has the gap probability e^(-G L / mu) on average at any facet size; what
// the size changes is how far one slab's gaps under the beam stray from that mean. Four slabs of
// each size (facets of 1.6, 0.8, 0.4 and 0.2 m: 1 800 to 280 000 triangles), 50 000 rays each
// (0.8 % Monte Carlo spread on the ground): the spread of the ground's return among the slabs
// falls as the facets shrink (measured 8.2, 2.7, 2.6 and 1.6 %: at least halved from 1.6 to
// 0.2 m), and the mean of the four slabs of the smallest facets gives both numbers within the
// layer test's 2 %.
TEST(FacetTransport, SmallRandomFacetsTendToTheTurbidLayersSingleScattering) {
  const double L = 3.0;
  const double canopy = 2.0 * 0.45 / 3.0 * (1.0 - std::exp(-L / 2.0));
  const double ground = 0.3 * std::exp(-L / 2.0);
  EXPECT_NEAR(canopy, 0.2331, 1e-4);  // the table's numbers
  EXPECT_NEAR(ground, 0.06694, 1e-5);
  constexpr int slabs = 4;
  std::vector<double> spread, mean_canopy, mean_ground;
  for (double side_m : {1.6, 0.8, 0.4, 0.2}) {
    double sum_c = 0.0, sum_g = 0.0, sum_sq = 0.0;
    for (int seed = 1; seed <= slabs; ++seed) {
      const SlabResult r = slab_single_scattering(side_m, 50000, seed);
      sum_c += r.canopy / slabs;
      sum_g += r.ground / slabs;
      sum_sq += std::pow(r.ground / ground - 1.0, 2) / slabs;
    }
    spread.push_back(std::sqrt(sum_sq));
    mean_canopy.push_back(sum_c);
    mean_ground.push_back(sum_g);
    const std::string size = std::to_string(side_m).substr(0, 3);
    RecordProperty("canopy_" + size, std::to_string(sum_c));
    RecordProperty("ground_" + size, std::to_string(sum_g));
    RecordProperty("ground_rms_error_" + size, std::to_string(spread.back()));
  }
  EXPECT_LT(spread.back(), 0.5 * spread.front());
  EXPECT_NEAR(mean_canopy.back() / canopy, 1.0, 0.02);
  EXPECT_NEAR(mean_ground.back() / ground, 1.0, 0.02);
}

// PHYSICS.md section 4: leaves that absorb nothing (rho 0.6 + tau 0.4 = 1), wood panels and soil
// of reflectance 1, and a periodic tile: everything the sun puts in leaves through the top, the
// albedo is 1 (to 0.5 %, as the turbid scene's test), brf following every order.
TEST(FacetTransport, NonAbsorbingFacetsConserveEnergyInBrf) {
  test_support::CrownScene base({}, {{{0.6}, {0.4}, {1.0}, 0.0}}, {1.0});
  Vegetation vegetation;
  vegetation.facets = {{facet_slab(2.0, 0.5, 40.0, 1.0, 7, true), {0.0, 0.0, 0.0}, 0.7, 1.0}};
  vegetation.leaf_materials = {1, 0};
  base.optics.foliage.push_back({{1.0}, {0.0}, {1.0}, &base.angles, 0.0});  // wood
  const Scene scene(base.device, build_ground_mesh(base.plane, base.frame, 40.0, 1.0e9),
                    vegetation);
  BrfTile tile;
  tile.half_size_m = 30.0;
  BrfOptions options;
  options.sun_direction = normalized(Vec3{0.3, 0.2, -1.0});
  options.views = {{0.0, 0.0, 1.0}};
  options.photons = 4000;
  options.seed = 3;
  options.image_pixels = 6;
  const BrfResult r = simulate_brf(scene, base.optics, tile, options);
  RecordProperty("albedo", std::to_string(r.albedo[0]));
  EXPECT_NEAR(r.albedo[0], 1.0, 0.005);
}

}  // namespace
}  // namespace glaswave
