// Airborne lidar point clouds -> a ground DEM and a voxel grid of plant area density, by
// gap-fraction inversion per column (MacArthur and Horn 1969; the ALS form of Hosoi and Omasa
// 2006, Béland et al. 2014 and AMAPVox, Vincent et al. 2017). The method, its assumptions and its
// biases are in docs/vegetation.md; in short:
//
//   - Ground (class 2) points, averaged per DEM cell, are interpolated with GDAL's gridding API
//     (GDALGridCreate, linear on a Delaunay triangulation, nearest point outside it).
//   - Every other point except noise (classes 7 and 18) and withheld points is a return of a
//     pulse; a return weighs 1 / number_of_returns, so that each pulse carries a weight of 1
//     however many returns it gave (return weighting, Armston et al. 2013).
//   - In each column, the fraction of the pulses' weight returned below height z above the DEM
//     is the gap fraction P(z) seen from above; Beer-Lambert through a layer [z0, z1] gives
//         PAD = cos(theta) / (G dz) * ln(P(z1) / P(z0)),
//     theta the column's mean scan angle from nadir, G the leaf projection (1/2 for spherical).
//   - A layer below which no weight passes (P(z0) = 0: occlusion) takes P(z0) = 1 / (2 W), W the
//     column's pulses: the densest value its sampling can tell. Layers under it stay empty.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "canopy/las_reader.hpp"
#include "canopy/voxel_grid.hpp"

namespace glaswave {

// A DEM on cell centres, row 0 the southernmost (y0 its southern edge, dy > 0).
struct GroundGrid {
  int nx = 0, ny = 0;
  double x0 = 0.0, y0 = 0.0, cell_m = 1.0;
  std::vector<float> height_m;  // [j * nx + i]; NaN where there is no ground

  // Bilinear between cell centres, clamped at the edges; NaN off the grid or without ground.
  double height_at(double x, double y) const;
};

// Ground points gridded over nx x ny cells of `cell_m` from (x0, y0): each cell's points
// averaged, then GDALGridCreate (linear, nearest beyond the triangulation). An input error
// naming `place` when there is no ground point.
GroundGrid grid_ground(const std::vector<std::array<double, 3>>& ground_points, double x0,
                       double y0, int nx, int ny, double cell_m, const std::string& place);

struct GapFractionSettings {
  double voxel_size_m = 1.0;     // columns and layers
  double leaf_projection = 0.5;  // G: 1/2 for spherical leaf angles
  double max_height_m = 120.0;   // returns higher above the ground are dropped as noise
};

struct VoxelizeReport {
  std::uint64_t points = 0, ground_points = 0, returns_used = 0, noise_dropped = 0;
  std::uint64_t occluded_layers = 0;  // layers where no weight passed (P(z0) = 0)
  std::uint64_t columns = 0, columns_with_pulses = 0;
};

// Accumulates returns into columns and layers, then inverts.
class GapFractionInversion {
 public:
  // Columns of the block's shape (x0, y0, nx, ny, dx = dy = voxel size), layers from 0 up to
  // nz * voxel size; `ground` gives heights above the ground.
  GapFractionInversion(const VoxelBlock& shape, const GroundGrid& ground,
                       const GapFractionSettings& settings);
  void add(const LasPoint& point, VoxelizeReport& report);
  VoxelBlock result(VoxelizeReport& report) const;

 private:
  VoxelBlock shape_;
  const GroundGrid* ground_;
  GapFractionSettings settings_;
  std::vector<double> weight_;   // [(column) * (nz + 1) + layer + 1]; slot 0 below ground
  std::vector<double> cos_sum_;  // per column: sum of weight * cos(scan angle)
  std::vector<double> column_weight_;
};

// A cloud's CRS and its ground gridded on the columns of its voxels (cells of voxel_size_m over
// its points' extent): the first pass of voxelize_point_cloud, and terrain.point_cloud's ground.
// An input error naming the file when it has no point, no ground or too many columns.
struct CloudGround {
  std::string crs_wkt;
  GroundGrid ground;
  std::uint64_t points = 0, ground_points = 0;
};
CloudGround grid_cloud_ground(const LasFile& cloud, const std::string& crs,
                              const std::string& crs_place, const GapFractionSettings& settings);

struct VoxelizeResult {
  VoxelBlock voxels;  // with the cloud's CRS
  GroundGrid ground;
  VoxelizeReport report;
};

// The whole of `voxelize` on a LAS file: two passes over its points (ground, then the rest), in
// windows, so that memory is the grid's, not the cloud's. `crs` is the fallback CRS. `ground`,
// when given, is this cloud's grid_cloud_ground at these settings (terrain.point_cloud's, already
// made): the first pass is skipped, the ground's Delaunay gridding being most of the time.
VoxelizeResult voxelize_point_cloud(const LasFile& cloud, const std::string& crs,
                                    const std::string& crs_place,
                                    const GapFractionSettings& settings,
                                    const CloudGround* ground = nullptr);

}  // namespace glaswave
