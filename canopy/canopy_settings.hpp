// What the configuration says about the vegetation (names of the seed's Table 1).
// Filled by pipeline/config, read by the canopy library.
#pragma once

#include <array>
#include <string>
#include <utility>
#include <vector>

namespace glaswave {

enum class LeafAngleDistribution {
  spherical,
  planophile,
  erectophile,
  plagiophile,
  extremophile,
  uniform,
  ellipsoidal,  // Campbell's, with a mean leaf inclination
};

enum class CrownShape { ellipsoid, cone, layer };

struct StandArea;

// A material of facet trees (canopy.facets.materials), per band: a leaf (its transmittance
// given) is two-sided bi-Lambertian, anything else opaque and Lambertian.
struct FacetMaterialSettings {
  std::string name;
  std::vector<double> reflectance;
  std::vector<double> transmittance;  // zeros for an opaque material
  bool leaf = false;
};

struct CanopySettings {
  // Which vegetation source grows it (pipeline/shot/vegetation_source.hpp): "forest", the
  // crowns, stands and layer below.
  std::string kind = "forest";
  double pai = 3.0;  // one-sided plant area (leaves and bark) per unit ground area of the scene
  LeafAngleDistribution lad = LeafAngleDistribution::spherical;
  double lad_mean_deg = 57.3;  // mean inclination, for `ellipsoidal` only
  double cover = 0.7;          // crown fractional cover
  double green_fraction = 0.8;
  double bark_fraction = 0.2;
  CrownShape crown_shape = CrownShape::ellipsoid;
  double crown_radius_m = 8.0;
  double crown_half_height_m = 8.0;
  std::array<double, 2> crown_base_m = {15.0, 20.0};  // min, max height of the crown base
  double leaf_size_m = 0.05;
  double dbh_m = 0.1;
  std::vector<double> leaf_reflectance;    // one value per sensor band
  std::vector<double> leaf_transmittance;  // one value per sensor band
  std::vector<double> bark_reflectance;    // one value per sensor band
  std::string crowns_file;                 // optional CSV of explicit crowns
  std::string stands;                      // optional GeoJSON of stands
  std::vector<StandArea> stand_areas;      // the stands file's polygons, read by pipeline/config
  // Measured vegetation (PRODUCT.md section 8): a voxel grid of plant area density
  // (canopy.voxels.file), or an airborne lidar point cloud voxelised at start
  // (canopy.point_cloud.file, its CRS when the file has none, the voxel size). Their leaves take
  // lad, leaf_size_m, leaf_reflectance, leaf_transmittance and bark_fraction above.
  std::string voxels_file;
  std::string point_cloud_file;
  std::string point_cloud_crs;
  double voxel_size_m = 1.0;
  // Facet trees (canopy.facets): the trees file, each model's name and mesh (or disc leaf)
  // file, the materials the meshes' material names map to, and the discs' material.
  std::string facet_trees_file;
  std::vector<std::pair<std::string, std::string>> facet_models;
  std::vector<FacetMaterialSettings> facet_materials;
  std::string facet_disc_material = "leaf";  // the material of every disc leaf model's discs
};

// A stand: polygons (lon, lat rings; a point is inside when an odd number of rings hold it, so
// holes work) where the canopy differs from the scene's.
struct StandArea {
  std::vector<std::vector<std::array<double, 2>>> rings;
  CanopySettings canopy;  // the scene's canopy with the stand's properties applied
};

}  // namespace glaswave
