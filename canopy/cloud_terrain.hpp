// The ground of an airborne lidar point cloud as the run's terrain (terrain.point_cloud,
// PRODUCT.md section 8): the cloud's class-2 points gridded on its voxels' columns exactly as
// `glaswave voxelize` writes ground_elevation (grid_cloud_ground), held as a GeoTIFF in GDAL's
// memory and read as any DEM is (terrain/dem_terrain.hpp), so that no DEM file is needed.
#pragma once

#include <memory>

#include "canopy/canopy_settings.hpp"
#include "canopy/gap_fraction.hpp"
#include "terrain/terrain.hpp"

namespace glaswave {

// canopy.point_cloud's ground (its file, CRS and voxel size) with the terrain's other settings
// (vertical datum, soil): an input error naming the file when the cloud cannot give one.
std::unique_ptr<Terrain> point_cloud_terrain(const TerrainSettings& terrain,
                                             const CanopySettings& canopy);

// The gridded ground a terrain of point_cloud_terrain stands on, for the voxelisation of the same
// cloud to take rather than grid it again (voxelize_point_cloud's `ground`); null for any other
// terrain.
std::shared_ptr<const CloudGround> cloud_ground_of(const Terrain& terrain);

}  // namespace glaswave
