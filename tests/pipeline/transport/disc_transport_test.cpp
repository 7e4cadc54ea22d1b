// Disc leaves through the lidar transport against numbers known without the code: one horizontal
// disc under a Gaussian beam (its return in closed form), a triangle and a 12-gon of its area
// (theirs by quadrature), a crown of discs against the same crown of equal-area 12-gons, and a
// slab of random small discs against PHYSICS.md section 3's turbid layer.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <numbers>
#include <random>
#include <vector>

#include "pipeline/scene/facet_model.hpp"
#include "pipeline/transport/shot_transport.hpp"
#include "tests/pipeline/transport/transport_test_support.hpp"

namespace glaswave {
namespace {

constexpr double range_m = 600000.0, beam_sigma_rad = 1e-5, ifov_rad = 4e-5;

// A nadir beam of 10 urad from 600 km (sigma 6 m on the ground) seen through a 40 urad field of
// view (12 m radius), one band of 1 mJ.
LidarSettings narrow_sensor() {
  LidarSettings sensor;
  sensor.pulse_sigma_ns = 5.0;
  sensor.divergence_sigma_rad = beam_sigma_rad;
  sensor.ifov_rad = ifov_rad;
  sensor.telescope_area_m2 = 0.709;
  sensor.bin_ns = 1.0;
  sensor.bins = 544;
  sensor.bands = {{1064.0, 1.0, 1.0, "1064"}};
  return sensor;
}

// E_t T A_T f_fov / (pi R^2): the unit in which a Lambertian plane filling the view returns rho.
double unit_J() {
  const double f_fov =
      1.0 - std::exp(-ifov_rad * ifov_rad / (8.0 * beam_sigma_rad * beam_sigma_rad));
  return 1e-3 * 0.709 * f_fov / (std::numbers::pi * range_m * range_m);
}

// A random direction uniform on the sphere, and two unit vectors across it.
struct Frame3 {
  Vec3 n, u, v;
};
Frame3 frame_of(const Vec3& n) {
  const Vec3 helper = std::abs(n[2]) < 0.9 ? Vec3{0.0, 0.0, 1.0} : Vec3{1.0, 0.0, 0.0};
  const Vec3 u = normalized(cross(n, helper));
  return {n, u, cross(n, u)};
}

// Regular polygons of `corners` corners and the area of a disc of radius r each, as triangle fans
// (one material).
std::shared_ptr<const FacetModel> polygons(const DiscLeaves& discs, int corners) {
  FacetMesh mesh;
  mesh.material_names = {"leaf"};
  const double a = 2.0 * std::numbers::pi / corners;
  // A regular n-gon of circumradius R has the area (n/2) R^2 sin(2 pi / n).
  const double per_r = std::sqrt(2.0 * std::numbers::pi / (corners * std::sin(a)));
  for (std::size_t d = 0; d < discs.size(); ++d) {
    const Vec3 c{discs.discs_m[4 * d], discs.discs_m[4 * d + 1], discs.discs_m[4 * d + 2]};
    const Frame3 f =
        frame_of({discs.normals[3 * d], discs.normals[3 * d + 1], discs.normals[3 * d + 2]});
    const double R = per_r * discs.discs_m[4 * d + 3];
    const auto first = static_cast<std::uint32_t>(mesh.vertices_m.size() / 3);
    for (int i = 0; i < 3; ++i) mesh.vertices_m.push_back(static_cast<float>(c[i]));
    for (int k = 0; k < corners; ++k) {
      const Vec3 p = c + R * std::cos(k * a) * f.u + R * std::sin(k * a) * f.v;
      for (int i = 0; i < 3; ++i) mesh.vertices_m.push_back(static_cast<float>(p[i]));
      mesh.triangles.insert(mesh.triangles.end(),
                            {first, first + 1 + k, first + 1 + (k + 1) % corners});
      mesh.materials.push_back(0);
    }
  }
  std::vector<int> materials(mesh.materials.size(), 0);
  return std::make_shared<const FacetModel>(std::move(mesh), std::move(materials));
}

// A shot at nadir over `model` (leaf material 0: rho 0.45, tau 0.45) standing at the origin on a
// ground of reflectance `soil`.
ShotWaveforms shoot(const std::shared_ptr<const FacetModel>& model, double soil, int max_order,
                    std::int64_t rays, std::uint64_t seed = 5) {
  test_support::CrownScene base({}, {{{0.45}, {0.45}, {0.45}, 0.0}}, {soil});
  Vegetation vegetation;
  vegetation.facets = {{model, {0.0, 0.0, 0.0}, 0.0, 1.0}};
  vegetation.leaf_materials = {1};
  const Scene scene(base.device, build_ground_mesh(base.plane, base.frame, 150.0, 1.0e9),
                    vegetation);
  const LidarModel lidar(narrow_sensor());
  TransportOptions options;
  options.rays = rays;
  options.max_order = max_order;
  options.seed = seed;
  return simulate_shot(scene, lidar, base.geometry, base.optics, options, 0);
}

DiscLeaves one_disc(double radius_m, double height_m) {
  DiscLeaves discs;
  discs.discs_m = {0.0f, 0.0f, static_cast<float>(height_m), static_cast<float>(radius_m)};
  discs.normals = {0.0f, 0.0f, 1.0f};
  return discs;
}

// The beam's part (of all its energy) falling on a horizontal shape centred under the beam, by
// a 5 mm grid over it: exp(-rho^2 / 2 s^2) / (2 pi s^2), s = R sigma_theta.
double beam_part(const std::function<bool(double, double)>& inside, double half_m) {
  const double s = range_m * beam_sigma_rad, step = 5e-3;
  double sum = 0.0;
  for (double x = -half_m + step / 2; x < half_m; x += step)
    for (double y = -half_m + step / 2; y < half_m; y += step)
      if (inside(x, y)) sum += std::exp(-(x * x + y * y) / (2.0 * s * s));
  return sum * step * step / (2.0 * std::numbers::pi * s * s);
}

// A horizontal bi-Lambertian disc of radius r, reflectance rho, 1 m over black ground, centred
// under a nadir Gaussian beam of RMS radius s = R sigma_theta = 6 m: it intercepts the part
// 1 - exp(-r^2 / 2 s^2) of the pulse and sends rho / pi of it per steradian straight up, so that
// E = E_t T rho / pi (1 - exp(-r^2 / 2 s^2)) A_T / R^2; in the unit E_t T A_T f_fov / (pi R^2),
// rho (1 - exp(-r^2 / 2 s^2)) / f_fov. For r = 6 m: 0.45 * 0.3935 / 0.8647 = 0.2048. Every ray
// that meets the disc scores the same, so the estimate is binomial: with the part p = 0.455 of
// the rays (drawn in the view) on it, its relative error is sqrt((1 - p) / (N p)) = 0.35 % at
// N = 100 000; to 1.5 % (4 sigma). A triangle and a 12-gon of the disc's area, centred, against
// the beam's part on each by quadrature (the triangle's corners reach farther into the beam's
// tail: 1.3 % less), with the same rays.
TEST(DiscTransport, OneDiscReturnsItsAreaTimesItsReflectanceAsAnEqualAreaPolygonDoes) {
  const double r = 6.0, s = range_m * beam_sigma_rad, rho = 0.45;
  const double f_fov = 1.0 - std::exp(-2.0);
  const double disc_expected = rho * (1.0 - std::exp(-r * r / (2.0 * s * s))) / f_fov;
  EXPECT_NEAR(disc_expected, 0.2048, 1e-4);
  const std::int64_t rays = 100000;
  const DiscLeaves disc = one_disc(r, 1.0);
  const ShotWaveforms w =
      shoot(std::make_shared<const FacetModel>(one_disc(r, 1.0), 0), 0.0, 1, rays);
  const double disc_return = w.canopy_energy_J[0] / unit_J();
  RecordProperty("disc", std::to_string(disc_return));
  EXPECT_NEAR(disc_return / disc_expected, 1.0, 0.015);
  EXPECT_EQ(w.ground_energy_J[0], 0.0);

  for (int corners : {3, 12}) {
    const double a = 2.0 * std::numbers::pi / corners;
    const double R = r * std::sqrt(2.0 * std::numbers::pi / (corners * std::sin(a)));
    // Inside a regular polygon of circumradius R with a corner on +x (the apothem R cos(a/2)).
    auto inside = [&](double x, double y) {
      for (int k = 0; k < corners; ++k) {
        const double phi = (k + 0.5) * a;
        if (x * std::cos(phi) + y * std::sin(phi) > R * std::cos(a / 2)) return false;
      }
      return true;
    };
    const double expected = rho * beam_part(inside, R) / f_fov;
    const ShotWaveforms p = shoot(polygons(disc, corners), 0.0, 1, rays);
    const double polygon_return = p.canopy_energy_J[0] / unit_J();
    RecordProperty("polygon_" + std::to_string(corners), std::to_string(polygon_return));
    RecordProperty("polygon_expected_" + std::to_string(corners), std::to_string(expected));
    EXPECT_NEAR(polygon_return / expected, 1.0, 0.015) << corners;
    // The same rays: the disc and the polygon differ by their shapes' beam parts alone.
    EXPECT_NEAR((disc_return / polygon_return) / (disc_expected / expected), 1.0, 0.01) << corners;
  }
}

// A crown of 3 000 discs of radius 0.15 m (normals uniform on the sphere) in a sphere of radius
// 4 m centred 8 m up, over soil of 0.3, to order 3: the same crown as 12-gons of equal area gives
// the same waveform. With the same rays, the two differ only where a ray passes a disc's rim
// (a 12-gon of its area covers 99.3 % of it and 0.7 % outside), a few tenths of a percent of the
// crown's return; bin by bin within 4 standard errors of the Monte Carlo (from the rays' spread)
// and in total within 1 %.
TEST(DiscTransport, DiscsAndEqualArea12GonsGiveTheSameWaveform) {
  std::mt19937_64 bits(17);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  DiscLeaves discs;
  while (discs.size() < 3000) {
    const Vec3 p{4.0 * u(bits), 4.0 * u(bits), 4.0 * u(bits)};
    if (norm(p) > 4.0) continue;
    Vec3 n{u(bits), u(bits), u(bits)};
    if (norm(n) > 1.0 || norm(n) < 1e-3) continue;
    n = normalized(n);
    discs.discs_m.insert(discs.discs_m.end(), {static_cast<float>(p[0]), static_cast<float>(p[1]),
                                               static_cast<float>(p[2] + 8.0), 0.15f});
    discs.normals.insert(discs.normals.end(), {static_cast<float>(n[0]), static_cast<float>(n[1]),
                                               static_cast<float>(n[2])});
  }
  const std::int64_t rays = 20000;
  const ShotWaveforms polygon = shoot(polygons(discs, 12), 0.3, 3, rays);
  const ShotWaveforms disc =
      shoot(std::make_shared<const FacetModel>(std::move(discs), 0), 0.3, 3, rays);
  RecordProperty("disc_canopy", std::to_string(disc.canopy_energy_J[0] / unit_J()));
  RecordProperty("polygon_canopy", std::to_string(polygon.canopy_energy_J[0] / unit_J()));
  EXPECT_GT(disc.canopy_energy_J[0], 0.02 * unit_J());  // the crown is seen
  EXPECT_NEAR(disc.canopy_energy_J[0] / polygon.canopy_energy_J[0], 1.0, 0.01);
  EXPECT_NEAR(disc.energy_J[0] / polygon.energy_J[0], 1.0, 0.01);
  double worst = 0.0;
  for (std::size_t b = 0; b < disc.total_W[0].size(); ++b) {
    const double sigma = std::sqrt(disc.total_variance_W2[0][b] + polygon.total_variance_W2[0][b]);
    if (sigma > 0.0)
      worst = std::max(worst, std::abs(disc.total_W[0][b] - polygon.total_W[0][b]) / sigma);
  }
  RecordProperty("worst_bin_sigmas", std::to_string(worst));
  EXPECT_LT(worst, 4.0);
}

// A slab 40 m wide, from 1 to 11 m, of discs of radius r with centres uniform in it and normals
// uniform on the sphere, as many as make L = 3: as the discs shrink, its single scattering tends
// to PHYSICS.md section 3's hotspot column, canopy (2 rho / 3)(1 - e^(-L/2)) = 0.2331 and ground
// rho_s e^(-L/2) = 0.06694 (as FacetTransport's test for triangles). Three sizes (r = 0.4, 0.2,
// 0.1 m: 3 000 to 150 000 discs), three slabs each, 30 000 rays each (1 % Monte Carlo error on
// the ground a slab): the mean of the smallest within 2.5 %, and the ground's spread among
// slabs no larger at 0.1 m than at 0.4 m.
TEST(DiscTransport, SmallRandomDiscsTendToTheTurbidLayersSingleScattering) {
  const double L = 3.0, half_m = 20.0;
  const double canopy = 2.0 * 0.45 / 3.0 * (1.0 - std::exp(-L / 2.0));
  const double ground = 0.3 * std::exp(-L / 2.0);
  EXPECT_NEAR(canopy, 0.2331, 1e-4);
  EXPECT_NEAR(ground, 0.06694, 1e-5);
  constexpr int slabs = 3;
  std::vector<double> spread, mean_canopy, mean_ground;
  for (double r : {0.4, 0.2, 0.1}) {
    double sum_c = 0.0, sum_g = 0.0, sum_sq = 0.0;
    for (int seed = 1; seed <= slabs; ++seed) {
      std::mt19937_64 bits(seed);
      auto uniform = [&bits] { return static_cast<double>(bits() >> 11) * 0x1.0p-53; };
      const auto count = static_cast<std::size_t>(
          std::llround(L * 4.0 * half_m * half_m / (std::numbers::pi * r * r)));
      DiscLeaves discs;
      for (std::size_t k = 0; k < count; ++k) {
        const double cos_t = 2.0 * uniform() - 1.0, phi = 2.0 * std::numbers::pi * uniform();
        const double sin_t = std::sqrt(1.0 - cos_t * cos_t);
        discs.discs_m.insert(discs.discs_m.end(),
                             {static_cast<float>((2.0 * uniform() - 1.0) * half_m),
                              static_cast<float>((2.0 * uniform() - 1.0) * half_m),
                              static_cast<float>(1.0 + 10.0 * uniform()), static_cast<float>(r)});
        discs.normals.insert(discs.normals.end(), {static_cast<float>(sin_t * std::cos(phi)),
                                                   static_cast<float>(sin_t * std::sin(phi)),
                                                   static_cast<float>(cos_t)});
      }
      const ShotWaveforms w =
          shoot(std::make_shared<const FacetModel>(std::move(discs), 0), 0.3, 1, 30000);
      const double c = w.canopy_energy_J[0] / unit_J(), g = w.ground_energy_J[0] / unit_J();
      sum_c += c / slabs;
      sum_g += g / slabs;
      sum_sq += std::pow(g / ground - 1.0, 2) / slabs;
    }
    spread.push_back(std::sqrt(sum_sq));
    mean_canopy.push_back(sum_c);
    mean_ground.push_back(sum_g);
    const std::string size = std::to_string(r).substr(0, 3);
    RecordProperty("canopy_" + size, std::to_string(sum_c));
    RecordProperty("ground_" + size, std::to_string(sum_g));
    RecordProperty("ground_rms_error_" + size, std::to_string(spread.back()));
  }
  EXPECT_LE(spread.back(), spread.front());
  EXPECT_NEAR(mean_canopy.back() / canopy, 1.0, 0.025);
  EXPECT_NEAR(mean_ground.back() / ground, 1.0, 0.025);
}

}  // namespace
}  // namespace glaswave
