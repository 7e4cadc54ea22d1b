// The forest behind the VegetationSource interface: a region holds the materials of the kinds it
// meets only, renumbered in the forest's order, so that a shot under one of thousands of stands
// projects one leaf angle table, not thousands.
#include "pipeline/shot/forest_source.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <set>

#include "pipeline/scene/scene.hpp"
#include "tests/pipeline/shot/shot_test_support.hpp"

namespace glaswave {
namespace {

using namespace glaswave::testing;

// A square stand of `half_deg` about (lat, lon).
StandArea square_stand(const CanopySettings& scene, double lat, double lon, double half_deg,
                       double leaf_reflectance) {
  StandArea stand;
  stand.rings = {{{lon - half_deg, lat - half_deg},
                  {lon + half_deg, lat - half_deg},
                  {lon + half_deg, lat + half_deg},
                  {lon - half_deg, lat + half_deg},
                  {lon - half_deg, lat - half_deg}}};
  stand.canopy = scene;
  stand.canopy.leaf_reflectance = {leaf_reflectance};
  return stand;
}

TEST(ForestSource, RegionHoldsOnlyTheKindsItMeets) {
  VegetationSettings settings;
  CanopySettings& canopy = settings.canopy;
  canopy.leaf_reflectance = {0.4};
  canopy.leaf_transmittance = {0.4};
  canopy.bark_reflectance = {0.3};
  canopy.cover = 0.7;
  canopy.crown_radius_m = 3.0;
  settings.plane = PlaneSettings{kLat0, kLon0, 0.0, 0.0, 0.0};
  // Kind 1 far to the north, kind 2 over the region (0.01 deg: about 1.1 km across).
  canopy.stand_areas = {square_stand(canopy, kLat0 + 1.0, kLon0, 0.01, 0.1),
                        square_stand(canopy, kLat0, kLon0, 0.01, 0.2)};
  const ForestSource source(settings);
  ASSERT_EQ(source.forest().kinds(), 3u);
  const std::unique_ptr<Terrain> terrain = plane_terrain();
  const LocalFrame frame(Geodetic{kLat0, kLon0, 0.0});
  const RegionVegetation grown = source.grow({*terrain, frame, 60.0, {}, 1});
  ASSERT_FALSE(grown.geometry.crowns.empty());
  ASSERT_EQ(grown.materials.size(), 1u);
  for (const Crown& crown : grown.geometry.crowns) EXPECT_EQ(crown.material, 0);
  for (int material : grown.geometry.trunk_materials) EXPECT_EQ(material, 0);
  // Kind 2's optics: f_green rho_leaf + f_bark rho_bark = 0.8 * 0.2 + 0.2 * 0.3.
  EXPECT_NEAR(grown.materials[0].reflectance[0], 0.22, 1e-15);
  EXPECT_EQ(grown.materials[0].leaf_angles, &source.forest().leaf_angles(2));
}

// Trunks are grids, a trunk each, of one material: a ray aimed level at a stem's axis meets the
// 8-sided prism under its crown where the prism's face at that bearing lies (the vertices on a
// circle of dbh / 2, faces between them: r cos(pi/8) / cos(its angle from the face's normal) from
// the axis), facing back along the ray, with the crown's material. Two stands of two barks.
TEST(ForestSource, TrunksAreGridsThatRaysMeetAsPrismsUnderTheirCrowns) {
  VegetationSettings settings;
  CanopySettings& canopy = settings.canopy;
  canopy.leaf_reflectance = {0.4};
  canopy.leaf_transmittance = {0.4};
  canopy.cover = 0.7;
  canopy.crown_radius_m = 3.0;
  canopy.dbh_m = 0.5;
  settings.plane = PlaneSettings{kLat0, kLon0, 0.0, 0.0, 0.0};
  canopy.bark_reflectance = {0.3};
  canopy.stand_areas = {square_stand(canopy, kLat0, kLon0 - 0.005, 0.005, 0.4)};
  canopy.bark_reflectance = {0.1};
  canopy.stand_areas.push_back(square_stand(canopy, kLat0, kLon0 + 0.005, 0.005, 0.4));
  const std::unique_ptr<Terrain> terrain = plane_terrain();
  const LocalFrame frame(Geodetic{kLat0, kLon0, 0.0});
  const RegionVegetation grown = ForestSource(settings).grow({*terrain, frame, 40.0, {}, 1});
  const Vegetation& vegetation = grown.geometry;
  ASSERT_GT(vegetation.trunks.grids.size(), 20u);
  ASSERT_TRUE(vegetation.trunks.triangles.empty());
  ASSERT_EQ(vegetation.trunk_materials.size(), vegetation.trunks.grids.size());
  EXPECT_EQ(
      std::set<int>(vegetation.trunk_materials.begin(), vegetation.trunk_materials.end()).size(),
      2u);

  const RayDevice device;
  const Scene scene(device, GroundMesh{}, vegetation);
  const double radius_m = 0.5 * canopy.dbh_m, from_m = 0.6, sector = std::numbers::pi / 4.0;
  std::mt19937_64 bits(3);
  std::uniform_real_distribution<double> turn(0.0, 2.0 * std::numbers::pi);
  int stems = 0;
  double worst_m = 0.0, worst_normal = 0.0;
  std::set<int> materials;
  for (const Crown& crown : vegetation.crowns) {
    // Stems with no other within 1.5 m: a ray from 0.6 m meets its own first.
    bool alone = true;
    for (const Crown& other : vegetation.crowns)
      if (&other != &crown &&
          std::hypot(other.base_m[0] - crown.base_m[0], other.base_m[1] - crown.base_m[1]) < 1.5)
        alone = false;
    if (!alone) continue;
    ++stems;
    materials.insert(crown.material);
    const Vec3 axis{crown.base_m[0], crown.base_m[1], crown.base_m[2] - 1.0};
    for (int k = 0; k < 16; ++k) {
      const double bearing = turn(bits);  // of the ray's origin from the axis, from east
      const Vec3 origin = axis + Vec3{from_m * std::cos(bearing), from_m * std::sin(bearing), 0.0};
      const SurfaceHit hit = scene.intersect(origin, normalized(axis - origin), 2.0);
      ASSERT_EQ(hit.kind, SurfaceKind::trunk)
          << "no trunk under the crown at " << axis[0] << ", " << axis[1];
      EXPECT_EQ(hit.material, crown.material);
      // The faces' normals point at pi/8 + k pi/4.
      const double off_normal = std::remainder(bearing - sector / 2.0, sector);
      const double face_m = radius_m * std::cos(sector / 2.0) / std::cos(off_normal);
      worst_m = std::max(worst_m, std::abs(hit.distance_m - (from_m - face_m)));
      const Vec3 facing{std::cos(bearing - off_normal), std::sin(bearing - off_normal), 0.0};
      worst_normal = std::max(worst_normal, norm(hit.normal - facing));
    }
  }
  EXPECT_GT(stems, 10);
  EXPECT_EQ(materials.size(), 2u);
  EXPECT_LT(worst_m, 1e-4);  // float vertices tens of metres from the frame's origin
  EXPECT_LT(worst_normal, 1e-4);
}

// Two stands side by side over the region, PAI 2 and 4 with the same optics: their crowns differ
// in density but scatter alike, so the region holds one material; other optics make a second.
TEST(ForestSource, KindsThatScatterAlikeShareOneMaterial) {
  VegetationSettings settings;
  CanopySettings& canopy = settings.canopy;
  canopy.leaf_reflectance = {0.4};
  canopy.leaf_transmittance = {0.4};
  canopy.bark_reflectance = {0.3};
  canopy.crown_radius_m = 3.0;
  settings.plane = PlaneSettings{kLat0, kLon0, 0.0, 0.0, 0.0};
  canopy.stand_areas = {square_stand(canopy, kLat0, kLon0 - 0.005, 0.005, 0.4),
                        square_stand(canopy, kLat0, kLon0 + 0.005, 0.005, 0.4)};
  canopy.stand_areas[0].canopy.pai = 2.0;
  canopy.stand_areas[1].canopy.pai = 4.0;
  const std::unique_ptr<Terrain> terrain = plane_terrain();
  const LocalFrame frame(Geodetic{kLat0, kLon0, 0.0});
  const RegionVegetation alike = ForestSource(settings).grow({*terrain, frame, 60.0, {}, 1});
  std::set<double> densities;
  for (const Crown& crown : alike.geometry.crowns) densities.insert(crown.area_density_m2_m3);
  EXPECT_EQ(densities.size(), 2u);
  EXPECT_EQ(alike.materials.size(), 1u);
  canopy.stand_areas[1].canopy.leaf_reflectance = {0.5};
  const RegionVegetation apart = ForestSource(settings).grow({*terrain, frame, 60.0, {}, 1});
  EXPECT_EQ(apart.materials.size(), 2u);
}

// Random crowns of cover c and radius r number -ln(1 - c) / (pi r^2) a square metre, each
// taking 2.5 KiB of a scene.
TEST(ForestSource, RegionBytesFromTheDensestKind) {
  VegetationSettings settings;
  settings.canopy.cover = 0.5;
  settings.canopy.crown_radius_m = 2.0;
  const double density = std::log(2.0) / (std::numbers::pi * 4.0);
  EXPECT_NEAR(vegetation_region_bytes(settings, 100.0), density * 1e4 * 2560.0, 1e-6);
  settings.canopy.crown_shape = CrownShape::layer;
  EXPECT_EQ(vegetation_region_bytes(settings, 100.0), 0.0);
}

}  // namespace
}  // namespace glaswave
