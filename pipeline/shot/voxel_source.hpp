// Measured vegetation as vegetation sources (PRODUCT.md section 8): a voxel grid of plant area
// density ("voxels": canopy.voxels.file, NetCDF or GeoTIFF), or an airborne lidar point cloud
// voxelised when the run starts ("point_cloud": canopy.point_cloud.file, by gap-fraction
// inversion, canopy/gap_fraction.hpp). Each shot's region is a window of the grid carried into
// the shot's frame, its columns standing on the terrain (pipeline/scene/voxel_field.hpp); every
// voxel is a turbid cell of one foliage: the canopy's leaves and bark, in proportion to
// bark_fraction.
#pragma once

#include <memory>

#include "canopy/leaf_angles.hpp"
#include "canopy/voxel_grid.hpp"
#include "pipeline/scene/voxel_field.hpp"
#include "pipeline/shot/vegetation_source.hpp"

namespace glaswave {

class VoxelSource : public VegetationSource {
 public:
  // Opens canopy.voxels_file, or reads and voxelises canopy.point_cloud_file: an input error
  // naming the file when it cannot be used.
  explicit VoxelSource(const VegetationSettings& settings);
  ~VoxelSource() override;

  RegionVegetation grow(const VegetationRegion& region) const override;
  // The grid's corners and edges' midpoints in WGS 84: a grid under no shot is warned about.
  std::vector<Placed> placed() const override;
  void check_region(const VegetationRegion& region) const override;
  bool checks_regions() const override { return true; }

  const VoxelGridFile& grid() const { return *grid_; }

  // A region `side_m` across: the ground under each column (a double), the columns' index, a
  // tile as read, and the grid's packed tiles it meets (VoxelFieldSource, all the grid's layers
  // of 4 bytes a column at most, as the file's header gives them) where the whole grid is more
  // than the tile cache keeps.
  static double region_bytes(const VegetationSettings& settings, double side_m);
  // What the source holds once: a NetCDF grid's decompressed chunks (VoxelGridFile::
  // read_cache_bytes); a point cloud's voxelisation when the run starts (its peak: the ground
  // points, or each voxel's weight and density; the grid it leaves is less); and the packed
  // tiles kept between shots (the whole grid, up to VoxelFieldSource::max_tile_cache_bytes).
  static double source_bytes(const VegetationSettings& settings);

 private:
  CanopySettings canopy_;
  LeafAngles leaf_angles_;
  std::unique_ptr<VoxelGridFile> grid_;
  std::unique_ptr<VoxelFieldSource> fields_;
};

}  // namespace glaswave
