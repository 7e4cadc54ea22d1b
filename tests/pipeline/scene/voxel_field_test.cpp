// The voxel DDA against a brute-force march: for random rays through fields over level and
// sloping ground, with rotated and sheared columns, the optical depth the spans give equals the
// integral of the density sampled every 0.5 mm along the ray, and the spans are ordered, do not
// overlap and stop when a free path has ended.
#include "pipeline/scene/voxel_field.hpp"

#include <cpl_conv.h>
#include <gtest/gtest.h>
#include <ogr_srs_api.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <thread>
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

// The traversal as it was before fields were packed column by column and empty layers skipped
// (voxel_field.cpp at a33b568), kept to check that the faster one gives the same spans to the
// bit.
struct ReferenceEmitter {
  std::vector<VolumeSpan>& spans;
  std::size_t first;  // spans before this index are not ours to merge with
  int material;
  const std::vector<double>* extinction_per_density;
  double depth_left;

  // Adds [t0, t1] at `density`; false when the free path has ended (stop).
  bool add(double t0, double t1, float density) {
    if (!(t1 > t0) || !(density > 0.0f)) return true;
    const double d = density;
    if (spans.size() > first && spans.back().end_m == t0 && spans.back().area_density_m2_m3 == d)
      spans.back().end_m = t1;
    else
      spans.push_back({t0, t1, d, material, -1});
    if (!extinction_per_density) return true;
    depth_left -= d * (*extinction_per_density)[material] * (t1 - t0);
    return depth_left > 0.0;
  }
};

void reference_spans(const VoxelField& f, const Vec3& origin, const Vec3& direction,
                     double max_distance_m, std::vector<VolumeSpan>& spans, double depth,
                     const std::vector<double>* extinction_per_density) {
  if (f.nx <= 0 || f.ny <= 0 || f.nz <= 0) return;
  // The ray in column coordinates (u, v): p = origin + u * axis_i + v * axis_j.
  const double a = f.axis_i_m[0], b = f.axis_j_m[0], c = f.axis_i_m[1], d = f.axis_j_m[1];
  const double det = a * d - b * c;
  if (det == 0.0) return;
  const double px = origin[0] - f.origin_m[0], py = origin[1] - f.origin_m[1];
  const double u0 = (d * px - b * py) / det, v0 = (a * py - c * px) / det;
  const double du = (d * direction[0] - b * direction[1]) / det;
  const double dv = (a * direction[1] - c * direction[0]) / det;
  double t_enter = 0.0, t_exit = max_distance_m;
  const auto clip = [&](double start, double rate, int n) {
    if (rate == 0.0) return start >= 0.0 && start < n;
    double t0 = (0.0 - start) / rate, t1 = (n - start) / rate;
    if (t0 > t1) std::swap(t0, t1);
    t_enter = std::max(t_enter, t0);
    t_exit = std::min(t_exit, t1);
    return true;
  };
  if (!clip(u0, du, f.nx) || !clip(v0, dv, f.ny) || !(t_enter < t_exit)) return;
  // Above the highest column and below the lowest there is nothing to meet.
  if (direction[2] != 0.0) {
    double t0 = (f.bottom_m - origin[2]) / direction[2],
           t1 = (f.ceiling_m - origin[2]) / direction[2];
    if (t0 > t1) std::swap(t0, t1);
    t_enter = std::max(t_enter, t0);
    t_exit = std::min(t_exit, t1);
    if (!(t_enter < t_exit)) return;
  } else if (!(origin[2] >= f.bottom_m && origin[2] <= f.ceiling_m)) {
    return;
  }

  const auto cell = [](double x, int n) {
    return std::clamp(static_cast<int>(std::floor(x)), 0, n - 1);
  };
  int i = cell(u0 + t_enter * du, f.nx), j = cell(v0 + t_enter * dv, f.ny);
  const double inf = std::numeric_limits<double>::infinity();
  const int step_i = du > 0.0 ? 1 : -1, step_j = dv > 0.0 ? 1 : -1;
  const double delta_i = du != 0.0 ? 1.0 / std::abs(du) : inf;
  const double delta_j = dv != 0.0 ? 1.0 / std::abs(dv) : inf;
  double next_i = du > 0.0 ? (i + 1 - u0) / du : du < 0.0 ? (i - u0) / du : inf;
  double next_j = dv > 0.0 ? (j + 1 - v0) / dv : dv < 0.0 ? (j - v0) / dv : inf;

  ReferenceEmitter emit{spans, spans.size(), f.material, extinction_per_density, depth};
  const std::vector<double>& edges = f.z_edges_m;
  const std::size_t columns = static_cast<std::size_t>(f.nx) * f.ny;
  const double oz = origin[2], dz = direction[2];
  for (double t_a = t_enter;;) {
    const double t_b = std::min({next_i, next_j, t_exit});
    const std::size_t column = static_cast<std::size_t>(j) * f.nx + i;
    const double ground = f.ground_m[column];
    if (t_b > t_a && std::isfinite(ground)) {
      const float* pad = f.pad.data() + column;
      if (dz == 0.0) {
        const double h = oz - ground;
        const auto above = std::upper_bound(edges.begin(), edges.end(), h);
        if (above != edges.begin() && above != edges.end()) {
          const std::size_t k = static_cast<std::size_t>(above - edges.begin()) - 1;
          if (!emit.add(t_a, t_b, pad[k * columns])) return;
        }
      } else {
        // Heights above this column's ground at the stretch's ends; the layers between them in
        // the order the ray crosses them.
        const double h_a = oz + t_a * dz - ground, h_b = oz + t_b * dz - ground;
        const double low = std::min(h_a, h_b), high = std::max(h_a, h_b);
        if (high > edges.front() && low < edges.back()) {
          int k_low =
              static_cast<int>(std::upper_bound(edges.begin(), edges.end(), low) - edges.begin()) -
              1;
          int k_high =
              static_cast<int>(std::lower_bound(edges.begin(), edges.end(), high) - edges.begin()) -
              1;
          k_low = std::max(k_low, 0);
          k_high = std::min(k_high, f.nz - 1);
          const int k_step = dz > 0.0 ? 1 : -1;
          const int k_first = dz > 0.0 ? k_low : k_high, k_last = dz > 0.0 ? k_high : k_low;
          for (int k = k_first;; k += k_step) {
            double t0 = (ground + edges[k] - oz) / dz, t1 = (ground + edges[k + 1] - oz) / dz;
            if (t0 > t1) std::swap(t0, t1);
            if (!emit.add(std::max(t0, t_a), std::min(t1, t_b), pad[k * columns])) return;
            if (k == k_last) break;
          }
        }
      }
    }
    if (t_b >= t_exit) return;
    if (next_i <= next_j) {
      i += step_i;
      next_i += delta_i;
      if (i < 0 || i >= f.nx) return;
    } else {
      j += step_j;
      next_j += delta_j;
      if (j < 0 || j >= f.ny) return;
    }
    t_a = t_b;
  }
}

bool same_bits(const std::vector<VolumeSpan>& a, const std::vector<VolumeSpan>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t n = 0; n < a.size(); ++n)
    if (a[n].start_m != b[n].start_m || a[n].end_m != b[n].end_m ||
        a[n].area_density_m2_m3 != b[n].area_density_m2_m3 || a[n].material != b[n].material ||
        a[n].crown != b[n].crown)
      return false;
  return true;
}

// Packed or not, the traversal gives the spans the former one gave, every bit of them, with
// and without a free path's end: over fields with runs of equal density (merged), empty
// columns and stretches, a column without ground, level and sloping ground; rays from above,
// inside, level, vertical, along column edges and layer heights.
TEST(VoxelSpans, PackedAndLayeredGiveTheFormerTraversalsBits) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0), unit(0.0, 1.0);
  const std::vector<double> extinction{0.5};
  for (int field = 0; field < 12; ++field) {
    VoxelField f;
    f.origin_m = {-20.0 + u(rng), -15.0 + u(rng)};
    f.axis_i_m = field % 3 == 0 ? std::array<double, 2>{1.0, 0.0} : std::array<double, 2>{1.1, 0.2};
    f.axis_j_m =
        field % 3 == 0 ? std::array<double, 2>{0.0, 1.0} : std::array<double, 2>{-0.1, 0.9};
    f.nx = 40;
    f.ny = 30;
    f.nz = 25;
    for (int k = 0; k <= f.nz; ++k) f.z_edges_m.push_back(field % 2 ? k : 0.5 * k + 0.01 * k * k);
    const double slope = field % 4 == 1 ? 0.3 : 0.0;
    for (int j = 0; j < f.ny; ++j)
      for (int i = 0; i < f.nx; ++i) f.ground_m.push_back(slope * (i - j) * 0.5);
    f.ground_m[7] = std::numeric_limits<double>::quiet_NaN();
    // Columns of crowns: a stretch of equal density with ragged ends, some columns empty.
    f.pad.assign(static_cast<std::size_t>(f.nx) * f.ny * f.nz, 0.0f);
    for (int j = 0; j < f.ny; ++j)
      for (int i = 0; i < f.nx; ++i) {
        if (unit(rng) < 0.3) continue;
        const int bottom = static_cast<int>(unit(rng) * 10), top = bottom + 1 + int(unit(rng) * 14);
        const float inside = unit(rng) < 0.5 ? 0.4f : static_cast<float>(unit(rng));
        for (int k = bottom; k < top && k < f.nz; ++k)
          f.pad[(static_cast<std::size_t>(k) * f.ny + j) * f.nx + i] =
              k == bottom || k == top - 1 || unit(rng) < 0.1 ? static_cast<float>(unit(rng))
              : unit(rng) < 0.1                              ? 0.0f
                                                             : inside;
      }
    f.bottom_m = -1.0 + (slope > 0 ? -20.0 : 0.0);
    f.ceiling_m = f.z_edges_m.back() + (slope > 0 ? 20.0 : 0.0);
    VoxelField packed = f;
    packed.pack();
    ASSERT_TRUE(packed.packed());
    EXPECT_TRUE(packed.pad.empty());
    EXPECT_EQ(packed.top_m(), f.top_m());
    for (int ray = 0; ray < 3000; ++ray) {
      Vec3 origin{18.0 * u(rng), 12.0 * u(rng), 30.0 + 5.0 * u(rng)};
      Vec3 direction = normalized(Vec3{u(rng), u(rng), -0.2 - unit(rng)});
      if (ray % 5 == 0) direction = normalized(Vec3{u(rng), u(rng), u(rng)});
      if (ray % 7 == 0) origin[2] = f.z_edges_m.back() * unit(rng);          // inside
      if (ray % 11 == 0) direction = {0.0, 0.0, ray % 2 ? -1.0 : 1.0};       // a column
      if (ray % 13 == 0) direction = normalized(Vec3{u(rng), u(rng), 0.0});  // level
      if (ray % 17 == 0) origin[2] = f.z_edges_m[ray % f.nz];                // on a layer's edge
      if (ray % 19 == 0) origin[0] = f.origin_m[0] + 3.0;                    // on a column's edge
      const double length = 80.0 * unit(rng), depth = 3.0 * unit(rng);
      for (const std::vector<double>* e :
           {static_cast<const std::vector<double>*>(nullptr), &extinction}) {
        std::vector<VolumeSpan> expected, layered, packed_spans;
        reference_spans(f, origin, direction, length, expected, depth, e);
        voxel_spans(f, origin, direction, length, layered, depth, e);
        voxel_spans(packed, origin, direction, length, packed_spans, depth, e);
        EXPECT_TRUE(same_bits(layered, expected)) << "field " << field << " ray " << ray;
        EXPECT_TRUE(same_bits(packed_spans, expected)) << "field " << field << " ray " << ray;
      }
    }
  }
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

// A grid of 300 x 300 columns (PAD in the upper layer = column number east + 1000 x row north,
// exact in float) is 5 x 5 tiles: every field's columns follow on from their neighbours across
// the tiles' seams, and a field keeps its tiles while a source caching none serves fields
// elsewhere, from one thread or four at once; the same columns as a source caching the whole
// grid serves.
TEST(VoxelFieldSource, FieldsKeepTheirTilesAcrossSeamsEvictionsAndThreads) {
  test_support::ScratchDir dir;
  VoxelBlock b;
  b.crs_wkt = "EPSG:32633";
  b.nx = b.ny = 300;
  b.nz = 2;
  b.dx = b.dy = 2.0;
  // UTM 33N of (45 N, 15 E) by gdaltransform: 500000.00, 4982950.40.
  b.x0 = 500000.0 - 300.0;
  b.y0 = 4982950.4 - 300.0;
  b.z_edges_m = {0.0, 5.0, 20.0};
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 300; ++j)
      for (int i = 0; i < 300; ++i) b.pad.push_back(k == 0 ? 0.0f : i + 1000.0f * j);
  write_voxel_netcdf(dir.path() / "pad.nc", b);
  const VoxelGridFile grid(dir.path() / "pad.nc");
  const VoxelFieldSource none_kept(grid, "pad.nc", 0), all_kept(grid, "pad.nc");
  const PlaneTerrain plane({45.0, 15.0, 300.0, 0.0, 0.0});
  const auto value = [](const VoxelField& f, int i, int j) {
    const VoxelField::Column& c = f.columns[static_cast<std::size_t>(j) * f.nx + i];
    EXPECT_EQ(c.first, 1);
    EXPECT_EQ(c.end, 2);
    return (*f.blocks[c.block])[c.offset];
  };
  const auto follow_on = [&](const VoxelField& f) {
    for (int j = 0; j < f.ny; ++j)
      for (int i = 0; i < f.nx; ++i) {
        if (i + 1 < f.nx) {
          ASSERT_EQ(value(f, i + 1, j) - value(f, i, j), 1.0f) << i << ", " << j;
        }
        if (j + 1 < f.ny) {
          ASSERT_EQ(value(f, i, j + 1) - value(f, i, j), 1000.0f) << i << ", " << j;
        }
      }
  };
  const LocalFrame centre({45.0, 15.0, 300.0});
  const auto held = none_kept.field(centre, plane, 200.0, 0);
  ASSERT_GT(held->nx, 150);
  EXPECT_GT(held->blocks.size(), 9u);
  for (const double lat : {44.9995, 45.0005, 45.001})
    follow_on(*none_kept.field(LocalFrame({lat, 15.0005, 300.0}), plane, 100.0, 0));
  follow_on(*held);
  const auto kept = all_kept.field(centre, plane, 200.0, 0);
  ASSERT_EQ(kept->nx, held->nx);
  ASSERT_EQ(kept->ny, held->ny);
  for (int j = 0; j < held->ny; ++j)
    for (int i = 0; i < held->nx; ++i) ASSERT_EQ(value(*held, i, j), value(*kept, i, j));
  // Four threads at once, each loading and dropping tiles the others need: the same columns.
  std::vector<std::thread> threads;
  std::vector<std::shared_ptr<const VoxelField>> fields(4);
  for (int k = 0; k < 4; ++k)
    threads.emplace_back([&, k] {
      for (int round = 0; round < 20; ++round)
        fields[k] = none_kept.field(LocalFrame({45.0 + 0.0002 * ((k + round) % 5), 15.0, 300.0}),
                                    plane, 150.0, 0);
      fields[k] = none_kept.field(centre, plane, 200.0, 0);
    });
  for (std::thread& thread : threads) thread.join();
  for (const auto& field : fields)
    for (int j = 0; j < held->ny; ++j)
      for (int i = 0; i < held->nx; ++i) ASSERT_EQ(value(*field, i, j), value(*kept, i, j));
}

}  // namespace
}  // namespace glaswave
