// The voxel DDA against a brute-force march: for random rays through fields over level and
// sloping ground, with rotated and sheared columns, the optical depth the spans give equals the
// integral of the density sampled every 0.5 mm along the ray, and the spans are ordered, do not
// overlap and stop when a free path has ended.
#include "pipeline/scene/voxel_field.hpp"

#include <cpl_conv.h>
#include <gtest/gtest.h>
#include <ogr_srs_api.h>

#include <cmath>
#include <random>
#include <vector>

#include "canopy/voxel_grid.hpp"
#include "pipeline/scene/scene.hpp"
#include "terrain/terrain.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

// A 12 x 9 field of 4 layers (0-2, 2-5, 5-6, 6-10 m) with random densities (a third empty), its
// columns along `axis_i`, `axis_j`, the ground rising as `slope_x` x + `slope_y` y under each
// column's centre.
VoxelField random_field(std::mt19937& rng, std::array<double, 2> axis_i,
                        std::array<double, 2> axis_j, double slope_x, double slope_y) {
  VoxelField f;
  f.origin_m = {-7.0, -5.0};
  f.axis_i_m = axis_i;
  f.axis_j_m = axis_j;
  f.nx = 12;
  f.ny = 9;
  f.nz = 4;
  f.z_edges_m = {0.0, 2.0, 5.0, 6.0, 10.0};
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int j = 0; j < f.ny; ++j)
    for (int i = 0; i < f.nx; ++i) {
      const double x = f.origin_m[0] + (i + 0.5) * axis_i[0] + (j + 0.5) * axis_j[0];
      const double y = f.origin_m[1] + (i + 0.5) * axis_i[1] + (j + 0.5) * axis_j[1];
      f.ground_m.push_back(slope_x * x + slope_y * y);
    }
  for (int n = 0; n < f.nx * f.ny * f.nz; ++n)
    f.pad.push_back(u(rng) < 0.33 ? 0.0f : static_cast<float>(u(rng)));
  return f;
}

// The density at a point, found independently of the DDA: the column by solving for the
// parallelogram coordinates, the layer by a linear scan.
double density_at(const VoxelField& f, const Vec3& p) {
  const double a = f.axis_i_m[0], b = f.axis_j_m[0], c = f.axis_i_m[1], d = f.axis_j_m[1];
  const double det = a * d - b * c, px = p[0] - f.origin_m[0], py = p[1] - f.origin_m[1];
  const double u = (d * px - b * py) / det, v = (a * py - c * px) / det;
  if (u < 0 || v < 0 || u >= f.nx || v >= f.ny) return 0.0;
  const int i = static_cast<int>(u), j = static_cast<int>(v);
  const double h = p[2] - f.ground_m[j * f.nx + i];
  for (int k = 0; k < f.nz; ++k)
    if (h >= f.z_edges_m[k] && h < f.z_edges_m[k + 1]) return f.pad[(k * f.ny + j) * f.nx + i];
  return 0.0;
}

TEST(VoxelSpans, OpticalDepthMatchesABruteForceMarch) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  struct Case {
    std::array<double, 2> axis_i, axis_j;
    double slope_x, slope_y;
  };
  const Case cases[] = {{{1.0, 0.0}, {0.0, 1.0}, 0.0, 0.0},
                        {{1.2, 0.1}, {-0.2, 0.9}, 0.3, -0.2},   // rotated, sheared, on a slope
                        {{0.9, 0.0}, {0.0, -1.1}, -0.5, 0.1}};  // rows southward
  for (const Case& c : cases) {
    const VoxelField f = random_field(rng, c.axis_i, c.axis_j, c.slope_x, c.slope_y);
    for (int ray = 0; ray < 300; ++ray) {
      Vec3 origin{4.0 * u(rng), 3.0 * u(rng), 14.0 + 3.0 * u(rng)};
      Vec3 direction = normalized(Vec3{u(rng), u(rng), ray % 7 == 0 ? 0.0 : -1.0 - u(rng)});
      if (ray % 11 == 0) direction = {0.0, 0.0, -1.0};    // straight down a column
      if (ray % 13 == 0) origin[2] = 3.0 + 2.0 * u(rng);  // starting inside the grid
      const double length = 40.0;
      std::vector<VolumeSpan> spans;
      voxel_spans(f, origin, direction, length, spans);
      double depth = 0.0, last_end = 0.0;
      for (const VolumeSpan& s : spans) {
        EXPECT_GE(s.start_m, last_end - 1e-12);
        EXPECT_GT(s.end_m, s.start_m);
        EXPECT_LE(s.end_m, length);
        EXPECT_EQ(s.crown, -1);
        last_end = s.end_m;
        depth += s.area_density_m2_m3 * (s.end_m - s.start_m);
      }
      double marched = 0.0;
      const double step = 5e-4;
      for (double t = step / 2; t < length; t += step)
        marched += density_at(f, origin + t * direction) * step;
      EXPECT_NEAR(depth, marched, 2e-3 * (1.0 + marched)) << "ray " << ray;
    }
  }
}

TEST(VoxelSpans, StopsWhereTheFreePathEnds) {
  VoxelField f;
  f.nx = f.ny = 1;
  f.nz = 10;
  f.axis_i_m = {100.0, 0.0};
  f.axis_j_m = {0.0, 100.0};
  f.origin_m = {-50.0, -50.0};
  for (int k = 0; k <= 10; ++k) f.z_edges_m.push_back(k);
  f.ground_m = {0.0};
  f.pad.assign(10, 0.0f);
  for (int k = 0; k < 10; k += 2) f.pad[k] = 0.5f;  // alternate layers empty
  std::vector<VolumeSpan> spans;
  voxel_spans(f, {0.0, 0.0, 20.0}, {0.0, 0.0, -1.0}, 30.0, spans);
  ASSERT_EQ(spans.size(), 5u);
  EXPECT_DOUBLE_EQ(spans[0].start_m, 11.0);   // layer 8-9 m, from 20 m
  const std::vector<double> extinction{0.5};  // G
  spans.clear();
  // 0.6 of depth: 0.25 a layer -> the third layer met holds the end.
  voxel_spans(f, {0.0, 0.0, 20.0}, {0.0, 0.0, -1.0}, 30.0, spans, 0.6, &extinction);
  ASSERT_EQ(spans.size(), 3u);
  EXPECT_DOUBLE_EQ(spans[2].end_m, 16.0);
  // Uniform density merges into one span through the layers and columns it crosses.
  f.pad.assign(10, 0.25f);
  spans.clear();
  voxel_spans(f, {0.0, 0.0, 20.0}, {0.0, 0.0, -1.0}, 30.0, spans);
  ASSERT_EQ(spans.size(), 1u);
  EXPECT_DOUBLE_EQ(spans[0].start_m, 10.0);
  EXPECT_DOUBLE_EQ(spans[0].end_m, 20.0);
  EXPECT_DOUBLE_EQ(f.top_m(), 10.0);
}

}  // namespace
}  // namespace glaswave

namespace glaswave {
namespace {

// A grid in UTM zone 33N (2 m columns, PAD = column number east + 0.01 x row north) under a
// shot at 45 N 15 E on a 10 degree slope facing east: straight down from above the footprint, a
// ray meets the column that holds the footprint's UTM position (found here through OGR, apart
// from the code under test), its layers standing on the plane's height there.
TEST(VoxelFieldSource, CarriesAWindowOfTheGridIntoTheShotsFrame) {
  test_support::ScratchDir dir;
  OGRSpatialReferenceH utm = OSRNewSpatialReference(nullptr), wgs = OSRNewSpatialReference(nullptr);
  OSRImportFromEPSG(utm, 32633);
  OSRImportFromEPSG(wgs, 4326);
  OSRSetAxisMappingStrategy(wgs, OAMS_TRADITIONAL_GIS_ORDER);
  OSRSetAxisMappingStrategy(utm, OAMS_TRADITIONAL_GIS_ORDER);
  double x = 15.0, y = 45.0;
  OGRCoordinateTransformationH to_utm = OCTNewCoordinateTransformation(wgs, utm);
  ASSERT_TRUE(OCTTransform(to_utm, 1, &x, &y, nullptr));
  OCTDestroyCoordinateTransformation(to_utm);
  VoxelBlock b;
  char* wkt = nullptr;
  OSRExportToWkt(utm, &wkt);
  b.crs_wkt = wkt;
  CPLFree(wkt);
  OSRDestroySpatialReference(utm);
  OSRDestroySpatialReference(wgs);
  b.nx = b.ny = 100;
  b.nz = 2;
  b.dx = b.dy = 2.0;
  b.x0 = std::floor(x) - 101.0;
  b.y0 = std::floor(y) - 99.0;
  b.z_edges_m = {0.0, 5.0, 20.0};
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 100; ++j)
      for (int i = 0; i < 100; ++i) b.pad.push_back(k == 0 ? 0.0f : i + 0.01f * j);
  write_voxel_netcdf(dir.path() / "pad.nc", b);
  const VoxelGridFile grid(dir.path() / "pad.nc");
  const VoxelFieldSource source(grid, "pad.nc");
  const PlaneTerrain plane({45.0, 15.0, 300.0, 10.0, 90.0});
  const LocalFrame frame({45.0, 15.0, 300.0});
  const auto field = source.field(frame, plane, 30.0, 3);
  ASSERT_GT(field->nx, 28);
  ASSERT_LT(field->nx, 34);
  EXPECT_EQ(field->material, 3);
  const int i = static_cast<int>((x - b.x0) / 2.0), j = static_cast<int>((y - b.y0) / 2.0);
  std::vector<VolumeSpan> spans;
  voxel_spans(*field, {0.0, 0.0, 100.0}, {0.0, 0.0, -1.0}, 200.0, spans);
  ASSERT_EQ(spans.size(), 1u);
  EXPECT_FLOAT_EQ(static_cast<float>(spans[0].area_density_m2_m3), i + 0.01f * j);
  // The column stands on the plane under its centre, within 2 m of the footprint: its height
  // there is within tan(10 deg) * 1.5 m of the footprint's.
  EXPECT_NEAR(spans[0].end_m, 100.0 - 5.0, 0.27);
  EXPECT_NEAR(spans[0].end_m - spans[0].start_m, 15.0, 1e-9);
  // The axes: 2 m cells, turned by the meridian convergence at the zone's centre (0 here).
  EXPECT_NEAR(field->axis_i_m[0], 2.0, 2.0 * 1e-3);
  EXPECT_NEAR(field->axis_i_m[1], 0.0, 1e-3);
}

}  // namespace
}  // namespace glaswave
