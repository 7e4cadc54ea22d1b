// Voxel grids and point clouds behind the VegetationSource interface.
#include "pipeline/shot/voxel_source.hpp"

#include <algorithm>
#include <limits>

#include "canopy/gap_fraction.hpp"
#include "canopy/las_reader.hpp"

namespace glaswave {

VoxelSource::VoxelSource(const VegetationSettings& settings)
    : canopy_(settings.canopy), leaf_angles_(canopy_.lad, canopy_.lad_mean_deg) {
  std::string place;
  if (canopy_.kind == "point_cloud") {
    place = canopy_.point_cloud_file;
    const LasFile cloud(canopy_.point_cloud_file);
    GapFractionSettings inversion;
    inversion.voxel_size_m = canopy_.voxel_size_m;
    inversion.leaf_projection = 0.5;  // what the inversion assumes; see docs/vegetation.md
    VoxelizeResult result =
        voxelize_point_cloud(cloud, canopy_.point_cloud_crs, "/canopy/point_cloud/crs", inversion);
    grid_ = std::make_unique<VoxelGridFile>(std::move(result.voxels));
  } else {
    place = canopy_.voxels_file;
    grid_ = std::make_unique<VoxelGridFile>(canopy_.voxels_file);
  }
  fields_ = std::make_unique<VoxelFieldSource>(*grid_, place);
}

VoxelSource::~VoxelSource() = default;

RegionVegetation VoxelSource::grow(const VegetationRegion& region) const {
  RegionVegetation grown;
  grown.geometry.trunks.max_height_m = -std::numeric_limits<double>::infinity();
  grown.geometry.voxels = fields_->field(region.frame, region.terrain, region.half_size_m, 0);
  // Plant-area weighted elements, as the forest's: leaves bi-Lambertian, bark opaque.
  Foliage foliage;
  const double bark = canopy_.bark_fraction, green = 1.0 - bark;
  for (std::size_t band = 0; band < region.bands; ++band) {
    foliage.reflectance.push_back(green * canopy_.leaf_reflectance[band] +
                                  bark * canopy_.bark_reflectance[band]);
    foliage.transmittance.push_back(green * canopy_.leaf_transmittance[band]);
  }
  foliage.trunk_reflectance = canopy_.bark_reflectance;
  foliage.leaf_angles = &leaf_angles_;
  foliage.leaf_size_m = canopy_.leaf_size_m;
  grown.materials.push_back(foliage);
  return grown;
}

double VoxelSource::region_bytes(const VegetationSettings& settings, double side_m) {
  const double cell_m = settings.canopy.kind == "point_cloud" ? settings.canopy.voxel_size_m : 1.0;
  const double columns = (side_m / cell_m + 1.0) * (side_m / cell_m + 1.0);
  return columns * (60.0 * sizeof(float) + sizeof(double));
}

}  // namespace glaswave
