// Facet trees as a vegetation source (PRODUCT.md sections 8 and 13, canopy.facets): triangle
// meshes read with Assimp or leaves as discs read from RAMI's `*.def` files, one shared model
// each (pipeline/scene/facet_model.hpp), placed by a trees file, each tree standing on the terrain
// under its stem (or floating z_m above it) as an Embree instance of its model.
// The meshes' material names map to the configuration's materials: leaves (a transmittance
// given) two-sided bi-Lambertian, the others (wood) Lambertian. The hotspot comes out of the
// geometry: the way back to the sensor runs through the same facets.
#pragma once

#include <memory>
#include <vector>

#include "canopy/facet_trees.hpp"
#include "canopy/leaf_angles.hpp"
#include "pipeline/scene/facet_model.hpp"
#include "pipeline/shot/vegetation_source.hpp"

namespace glaswave {

// What a model takes at its peak (Assimp's read, the mesh and its BVH) for a byte of its file:
// facet_benchmark's OBJ of 100 016 triangles, 10.6 MB, took the process to a peak of 242 MiB
// (about 210 MiB above its start; 131 MiB kept after the read). Binary meshes (PLY, glb) hold
// about twice the triangles a byte: their estimate may be half what they take.
inline constexpr double facet_model_bytes_per_file_byte = 20.0;
// A disc leaf file (RAMI's `.def`, about 65 bytes a disc) is read without Assimp: each disc's
// centre, normal and radius, and Embree's point and BVH, came to 1.2 bytes a byte of the file
// (HET01's sphere of 49 999 discs, 3.27 MB: a run's peak 3.9 MB above bare ground's) and 1.7
// (a HOM layer's 2.53 MB, with its region's copies); 2, to stay above both.
inline constexpr double disc_model_bytes_per_file_byte = 2.0;

class FacetSource : public VegetationSource {
 public:
  // Reads every model's mesh and the trees file: an input error naming the file when one cannot
  // be used, or when a mesh's material has no entry in canopy.facets.materials.
  explicit FacetSource(const VegetationSettings& settings);

  RegionVegetation grow(const VegetationRegion& region) const override;

  // Cover and height along vertical lines, the plant area from the facets' own area.
  VegetationTruth truth(const Scene& scene, const BeamSpot& spot,
                        const std::vector<double>& nadir_projection) const override;

  std::vector<Placed> placed() const override;
  bool fixed_on_the_ground() const override { return true; }  // trees placed on the Earth
  bool measured_on_volumes() const override { return false; }

  const std::vector<std::shared_ptr<const FacetModel>>& models() const { return models_; }
  const std::vector<FacetTree>& trees() const { return trees_; }

  // A region's instances, at a tree every 20 m² (a dense plot) and 256 bytes a tree (the models
  // themselves are shared by every shot).
  static double region_bytes(const VegetationSettings& settings, double side_m);
  // Every model, read once for the run: facet_model_bytes_per_file_byte times its file's size
  // (disc_model_bytes_per_file_byte for a disc leaf file).
  static double source_bytes(const VegetationSettings& settings);

 private:
  std::vector<std::shared_ptr<const FacetModel>> models_;
  std::vector<FacetTree> trees_;
  std::vector<FacetMaterialSettings> materials_;
  LeafAngles leaf_angles_{LeafAngleDistribution::spherical, 57.3};  // unused by facets
};

}  // namespace glaswave
