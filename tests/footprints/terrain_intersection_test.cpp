// The ray against steep terrain: the first crossing along the ray, as a brute-force march in
// 0.25 m steps finds it, on hills where slanted rays pass over several crests first.
#include "footprints/terrain_intersection.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "tests/footprints/test_terrains.hpp"

namespace glaswave {
namespace {

constexpr double deg = std::numbers::pi / 180.0;

struct Ray {
  Vec3 origin, direction;
};

// A ray from `altitude_m` above the hills' frame, at `zenith_deg` from its vertical toward
// `azimuth_deg`, aimed at (east_m, north_m) at height 0 of the frame.
Ray slanted_ray(const testing::SteepHills& hills, double east_m, double north_m, double altitude_m,
                double zenith_deg, double azimuth_deg) {
  const double s = std::sin(zenith_deg * deg), c = std::cos(zenith_deg * deg);
  const double length_m = altitude_m / c;
  const double e0 = east_m - length_m * s * std::sin(azimuth_deg * deg);
  const double n0 = north_m - length_m * s * std::cos(azimuth_deg * deg);
  double lat = 0, lon = 0, h = 0;
  hills.frame().Reverse(e0, n0, altitude_m, lat, lon, h);
  const Vec3 origin = ecef_from_geodetic({lat, lon, h});
  hills.frame().Reverse(east_m, north_m, 0.0, lat, lon, h);
  return {origin, normalized(ecef_from_geodetic({lat, lon, h}) - origin)};
}

double clearance_m(const Terrain& terrain, const Ray& ray, double t) {
  const Geodetic p = geodetic_from_ecef(ray.origin + t * ray.direction);
  return p.h_m - terrain.height_m(p.lat_deg, p.lon_deg);
}

struct BruteForce {
  double t = -1.0;  // first crossing, or -1
  int crossings = 0;
};

// Steps of 0.25 m from above the highest hill to below the lowest valley, then bisection.
BruteForce brute_force(const Terrain& terrain, const Ray& ray) {
  // Where the ray is 3000 m and 100 m above the ellipsoid (the hills span 200..2800 m).
  auto height_crossing = [&](double height_m) {
    double lo = 0, hi = 2.0e6;
    for (int i = 0; i < 100; ++i) {
      const double mid = 0.5 * (lo + hi);
      (geodetic_from_ecef(ray.origin + mid * ray.direction).h_m > height_m ? lo : hi) = mid;
    }
    return lo;
  };
  const double start = height_crossing(3000.0), end = height_crossing(100.0);
  BruteForce result;
  double previous = clearance_m(terrain, ray, start);
  for (double t = start + 0.25; t <= end; t += 0.25) {
    const double current = clearance_m(terrain, ray, t);
    if ((previous > 0) != (current > 0)) {
      if (++result.crossings == 1) {
        double lo = t - 0.25, hi = t;
        for (int i = 0; i < 60; ++i) {
          const double mid = 0.5 * (lo + hi);
          (clearance_m(terrain, ray, mid) > 0 ? lo : hi) = mid;
        }
        result.t = 0.5 * (lo + hi);
      }
    }
    previous = current;
  }
  return result;
}

TEST(IntersectTerrain, FindsTheFirstCrossingOnSteepHills) {
  const testing::SteepHills hills(46.5, 8.0);
  std::mt19937_64 random(12345);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  int rays = 0, several_crossings = 0;
  double worst_m = 0.0;
  long queries = 0;
  for (int i = 0; i < 120; ++i) {
    // Spaceborne rays up to 30 degrees from the vertical, and a third grazing ones from 20 km.
    const bool grazing = i % 3 == 2;
    const double zenith = grazing ? 50.0 + 30.0 * uniform(random) : 30.0 * uniform(random);
    const Ray ray =
        slanted_ray(hills, 6000.0 * (uniform(random) - 0.5), 6000.0 * (uniform(random) - 0.5),
                    grazing ? 20000.0 : 600000.0, zenith, 360.0 * uniform(random));
    const BruteForce expected = brute_force(hills, ray);
    IntersectionStats stats;
    const auto hit = intersect_terrain(hills, ray.origin, ray.direction, {}, &stats);
    queries += stats.height_queries;
    ASSERT_EQ(hit.has_value(), expected.t >= 0) << "ray " << i;
    if (!hit) continue;
    ++rays;
    several_crossings += expected.crossings > 1;
    const double error_m = norm(*hit - (ray.origin + expected.t * ray.direction));
    worst_m = std::max(worst_m, error_m);
    EXPECT_LT(error_m, 0.01) << "ray " << i << ", zenith " << zenith << ", " << expected.crossings
                             << " crossings";
    // On the ground to the centimetre.
    const Geodetic ground = geodetic_from_ecef(*hit);
    EXPECT_NEAR(ground.h_m, hills.height_m(ground.lat_deg, ground.lon_deg), 0.01);
  }
  // The test means something only if many rays cross the ground more than once.
  // (25 of these 120 do.)
  EXPECT_GE(several_crossings, 15) << several_crossings << " of " << rays;
  RecordProperty("worst_error_mm", std::to_string(worst_m * 1000.0));
  RecordProperty("height_queries_per_ray", std::to_string(queries / 120));
}

TEST(IntersectTerrain, ARayOverTerrainWithoutDataHasNoFootprint) {
  // Ground only 5 km around (1, 1); a nadir ray over (0, 0) sees no data all the way down.
  const testing::CapTerrain terrain(1.0, 1.0, 5000.0);
  const Vec3 spacecraft = ecef_from_geodetic({0.0, 0.0, 600000.0});
  IntersectionStats stats;
  EXPECT_FALSE(
      intersect_terrain(terrain, spacecraft, -1.0 * enu_axes(0, 0)[2], {}, &stats).has_value());
  EXPECT_LT(stats.height_queries, 20);
  // Over the data it lands.
  const Vec3 above = ecef_from_geodetic({1.0, 1.0, 600000.0});
  const auto hit = intersect_terrain(terrain, above, -1.0 * enu_axes(1, 1)[2]);
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(geodetic_from_ecef(*hit).h_m, 0.0, 0.01);
}

TEST(IntersectTerrain, AnOriginUnderTheGroundHasNoFootprint) {
  const testing::LevelTerrain terrain(500.0);
  const Vec3 origin = ecef_from_geodetic({10.0, 20.0, 100.0});
  EXPECT_FALSE(intersect_terrain(terrain, origin, -1.0 * enu_axes(10, 20)[2]).has_value());
}

}  // namespace
}  // namespace glaswave
