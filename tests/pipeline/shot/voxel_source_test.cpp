// The voxel grid and point cloud sources through the whole shot (footprint, terrain, scene,
// transport, receiver). A NetCDF grid of uniform density in UTM, wider than the beam, is PHYSICS.md
// section 3's layer: L = 3 (0.3 m2/m3 over 10 m), rho 0.45, soil 0.3, 5 cm leaves (the hotspot):
// single scattering 0.2331 (canopy) and 0.06694 (ground), to 2 % at 40 000 rays; its truth PAI 3,
// cover 1, height 10 m. A point cloud source grows the grid `voxelize` makes of its file.
#include "pipeline/shot/voxel_source.hpp"

#include <cpl_conv.h>
#include <gtest/gtest.h>
#include <ogr_srs_api.h>

#include <cmath>
#include <numbers>

#include "canopy/gap_fraction.hpp"
#include "canopy/voxel_grid.hpp"
#include "tests/canopy/las_fixture.hpp"
#include "tests/pipeline/shot/shot_test_support.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

using namespace glaswave::testing;

std::string utm_wkt(int epsg) {
  OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
  OSRImportFromEPSG(srs, epsg);
  char* wkt = nullptr;
  OSRExportToWkt(srs, &wkt);
  std::string text = wkt;
  CPLFree(wkt);
  OSRDestroySpatialReference(srs);
  return text;
}

// 600 m square of 3 m columns about the test footprint (45 N 7 E: UTM 32N, x 342 369, y 4 984 896).
VoxelBlock uniform_grid() {
  VoxelBlock b;
  b.crs_wkt = utm_wkt(32632);
  b.nx = b.ny = 200;
  b.nz = 5;
  b.dx = b.dy = 3.0;
  b.x0 = 342369.0 - 300.0;
  b.y0 = 4984896.0 - 300.0;
  b.z_edges_m = {0.0, 2.0, 4.0, 6.0, 8.0, 10.0};
  b.pad.assign(200 * 200 * 5, 0.3f);
  return b;
}

VegetationSettings voxel_settings(const std::string& file) {
  VegetationSettings settings;
  settings.canopy.kind = "voxels";
  settings.canopy.voxels_file = file;
  settings.canopy.leaf_size_m = 0.05;
  settings.canopy.bark_fraction = 0.0;
  settings.canopy.green_fraction = 1.0;
  settings.canopy.leaf_reflectance = {0.45};
  settings.canopy.leaf_transmittance = {0.45};
  settings.canopy.bark_reflectance = {0.3};
  return settings;
}

TEST(VoxelSource, UniformGridGivesTheTurbidLayer) {
  test_support::ScratchDir dir;
  write_voxel_netcdf(dir.path() / "pad.nc", uniform_grid());
  const std::unique_ptr<Terrain> terrain = plane_terrain(0.3);
  ShotSettings settings = shot_settings(0.3, 40000);
  settings.transport.max_order = 1;
  const ShotSimulator simulator(
      settings, *terrain, make_vegetation_source(voxel_settings((dir.path() / "pad.nc").string())),
      make_receiver(receiver_settings(settings, "waveform")));
  const Footprint footprint = nadir_footprint(*terrain);
  const ShotRecord record = simulator.simulate(footprint);
  ASSERT_EQ(record.quality_flag, quality_good);
  const double f_fov = 1.0 - std::exp(-0.0004 * 0.0004 / (8.0 * 0.00011 * 0.00011));
  const double normalisation =
      1e-3 * 0.709 * f_fov / (std::numbers::pi * footprint.range_m * footprint.range_m);
  const double canopy = record.rx_energy_canopy_J[0] / normalisation;
  const double ground = record.rx_energy_ground_J[0] / normalisation;
  EXPECT_NEAR(canopy / (2.0 * 0.45 / 3.0 * (1.0 - std::exp(-1.5))), 1.0, 0.02) << canopy;
  EXPECT_NEAR(ground / (0.3 * std::exp(-1.5)), 1.0, 0.02) << ground;
  EXPECT_NEAR(record.pai_true, 3.0, 1e-4);
  EXPECT_NEAR(record.cover_true, 1.0, 1e-9);
  EXPECT_NEAR(record.canopy_height_true_m, 10.0, 0.01);
}

TEST(VoxelSource, PointCloudGrowsItsVoxelisedGrid) {
  test_support::ScratchDir dir;
  test::LasFixture f;
  f.version_minor = 4;
  f.point_format = 6;
  f.offset[0] = 342000.0;
  f.offset[1] = 4985000.0;
  for (int j = 0; j < 40; ++j)
    for (int i = 0; i < 40; ++i) {
      test::LasFixturePoint p;
      p.x = 342369.0 - 20.0 + i + 0.5;
      p.y = 4984896.0 - 20.0 + j + 0.5;
      const bool hit = (i + j) % 3 == 0;
      p.z = hit ? 12.0 : 0.0;
      p.classification = hit ? 5 : 2;
      f.points.push_back(p);
    }
  test::write_las(dir.path() / "plot.las", f);
  VegetationSettings settings = voxel_settings("");
  settings.canopy.kind = "point_cloud";
  settings.canopy.point_cloud_file = (dir.path() / "plot.las").string();
  settings.canopy.point_cloud_crs = "EPSG:32632";
  settings.canopy.voxel_size_m = 4.0;
  const std::unique_ptr<VegetationSource> source = make_vegetation_source(settings);
  const std::unique_ptr<Terrain> terrain = plane_terrain(0.3);
  const LocalFrame frame({kLat0, kLon0, 0.0});
  const RegionVegetation grown = source->grow({*terrain, frame, 30.0, {}, 1});
  ASSERT_TRUE(grown.geometry.voxels);
  ASSERT_EQ(grown.materials.size(), 1u);
  // Straight down the footprint's column: one stretch, 12-16 m above the ground, of the density
  // gap-fraction inversion gives a column hit by a third of its pulses.
  std::vector<VolumeSpan> spans;
  voxel_spans(*grown.geometry.voxels, {1.0, 1.0, 100.0}, {0.0, 0.0, -1.0}, 200.0, spans);
  ASSERT_EQ(spans.size(), 1u);
  EXPECT_NEAR(spans[0].end_m - spans[0].start_m, 4.0, 1e-6);
  EXPECT_GT(spans[0].area_density_m2_m3, 0.0);
  EXPECT_LT(spans[0].area_density_m2_m3, 0.5);
}

}  // namespace
}  // namespace glaswave
