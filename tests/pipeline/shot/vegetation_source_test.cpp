// The VegetationSource interface holds sources other than the forest: two test doubles, each one
// class and one registration, run through the shot with no edit to the engine or the transport.
// They sketch the next issue's two: a grid of turbid voxels (here one voxel spanning the region,
// a slab) and a triangle mesh with a material per triangle (here a plate of two triangles).
#include "pipeline/shot/vegetation_source.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "canopy/leaf_angles.hpp"
#include "pipeline/shot/forest_source.hpp"
#include "tests/pipeline/shot/shot_test_support.hpp"

namespace glaswave {
namespace {

using namespace glaswave::testing;

// One turbid voxel spanning the region between 5 and 15 m: plant area density 0.5 m2/m3, so
// PAI 5 along every vertical line.
class OneVoxelSource : public VegetationSource {
 public:
  RegionVegetation grow(const VegetationRegion& region) const override {
    RegionVegetation grown;
    grown.geometry.trunks.max_height_m = -std::numeric_limits<double>::infinity();
    grown.geometry.layer = TurbidLayer{0.0, 0.0, 5.0, 15.0, 0.5, 0};
    Foliage leaves;
    leaves.reflectance.assign(region.bands, 0.45);
    leaves.transmittance.assign(region.bands, 0.45);
    leaves.trunk_reflectance.assign(region.bands, 0.3);
    leaves.leaf_angles = &angles_;
    grown.materials = {leaves};
    return grown;
  }

 private:
  LeafAngles angles_{LeafAngleDistribution::spherical, 57.3};
};

// An opaque plate 10 m above the ground covering the region, split along its diagonal through
// the footprint centre into two triangles of Lambertian reflectance 0.6 and 0.2.
class PlateSource : public VegetationSource {
 public:
  RegionVegetation grow(const VegetationRegion& region) const override {
    RegionVegetation grown;
    GroundMesh& mesh = grown.geometry.trunks;
    const auto h = static_cast<float>(region.half_size_m);
    mesh.vertices_m = {-h, -h, 10.0f, h, -h, 10.0f, h, h, 10.0f, -h, h, 10.0f};
    mesh.triangles = {0, 1, 2, 0, 2, 3};
    mesh.max_height_m = 10.0;
    grown.geometry.trunk_materials = {0, 1};
    for (double reflectance : {0.6, 0.2}) {
      Foliage facet;
      facet.reflectance.assign(region.bands, 0.0);
      facet.transmittance.assign(region.bands, 0.0);
      facet.trunk_reflectance.assign(region.bands, reflectance);
      facet.leaf_angles = &angles_;
      grown.materials.push_back(facet);
    }
    return grown;
  }

 private:
  LeafAngles angles_{LeafAngleDistribution::spherical, 57.3};
};

double region_bytes(const VegetationSettings&, double side_m) { return 64.0 * side_m; }

// Each test double registered once, as a new source is, from its own file.
const Registration<VegetationSource> one_voxel("one_voxel", 0,
                                               {[](const VegetationSettings&) {
                                                  return std::make_unique<OneVoxelSource>();
                                                },
                                                region_bytes, nullptr, "/canopy/one_voxel"});
const Registration<VegetationSource> plate("plate", 0,
                                           {[](const VegetationSettings&) {
                                              return std::make_unique<PlateSource>();
                                            },
                                            region_bytes, nullptr, "/canopy/plate"});

ShotRecord simulate(const std::string& kind, double soil_reflectance) {
  const std::unique_ptr<Terrain> terrain = plane_terrain(soil_reflectance);
  const ShotSettings settings = shot_settings(soil_reflectance);
  std::unique_ptr<VegetationSource> vegetation;
  if (!kind.empty()) {
    VegetationSettings source;
    source.canopy.kind = kind;
    vegetation = make_vegetation_source(source);
  }
  const ShotSimulator simulator(settings, *terrain, std::move(vegetation),
                                make_receiver(receiver_settings(settings, "waveform")));
  return simulator.simulate(nadir_footprint(*terrain));
}

TEST(VegetationSource, RegistersOnceByKind) {
  VegetationSettings settings;
  settings.canopy.kind = "one_voxel";
  EXPECT_EQ(vegetation_region_bytes(settings, 100.0), 6400.0);
  EXPECT_THROW(Registration<VegetationSource>("one_voxel", 0, {}), std::logic_error);
  settings.canopy.kind = "no_such_source";
  EXPECT_THROW(make_vegetation_source(settings), Error);
}

// Along every vertical line the voxel holds 0.5 m2/m3 over 10 m: PAI 5, cover 1, gap probability
// e^-5/2 (spherical leaves, G = 1/2 to the 2e-4 of the leaf-angle table: 5 e^-5/2 2e-4 = 8e-5),
// height 15 m
// (above a ground at constant height over the curved ellipsoid, which falls 4 mm below the
// frame's plane 230 m out: hence 1 cm).
TEST(VegetationSource, OneVoxelTruthAndReturns) {
  const ShotRecord record = simulate("one_voxel", 0.25);
  ASSERT_EQ(record.quality_flag, quality_good);
  EXPECT_NEAR(record.pai_true, 5.0, 1e-6);
  EXPECT_NEAR(record.cover_true, 1.0, 1e-12);
  EXPECT_NEAR(record.pgap_true, std::exp(-2.5), 1e-4);
  EXPECT_NEAR(record.canopy_height_true_m, 15.0, 1e-2);
  EXPECT_GT(record.rx_energy_canopy_J[0], 0.0);
}

// A Lambertian plate whose two halves reflect 0.6 and 0.2 returns what a ground of 0.4 does (the
// beam is symmetric about the diagonal; nothing above the plate scatters back), 10 m higher:
// its centroid lies 10 m above the ground's, to 0.1 m (a 1 ns bin is 0.15 m).
TEST(VegetationSource, PlateOfTwoMaterialsPerTriangle) {
  const ShotRecord plate = simulate("plate", 0.25);
  const ShotRecord ground = simulate("", 0.4);
  ASSERT_EQ(plate.quality_flag, quality_good);
  // Each of 2000 rays scores its triangle's reflectance: the binomial spread of the mean is
  // 0.2 / 0.4 / sqrt(2000) = 1.1 %; 4 % is 3.5 of it.
  EXPECT_NEAR(plate.rx_energy_J[0] / ground.rx_energy_J[0], 1.0, 0.04);
  EXPECT_NEAR(plate.centroid_m[0] - ground.centroid_m[0], 10.0, 0.1);
  EXPECT_EQ(plate.rx_energy_ground_J[0], 0.0);
  EXPECT_EQ(plate.pai_true, 0.0);  // no volumes: the default truth sees none
  EXPECT_EQ(plate.pgap_true, 1.0);
}

}  // namespace
}  // namespace glaswave
