// Facet trees behind the VegetationSource interface.
#include "pipeline/shot/facet_source.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <numbers>

#include "core/error.hpp"

namespace glaswave {

FacetSource::FacetSource(const VegetationSettings& settings)
    : materials_(settings.canopy.facet_materials) {
  const CanopySettings& canopy = settings.canopy;
  std::vector<std::string> names;
  for (const auto& [name, file] : canopy.facet_models) {
    if (is_disc_leaf_file(file)) {
      // Leaves as discs, all of canopy.facets.disc_material.
      DiscLeaves discs = read_disc_leaves(file, name);
      const auto found = std::find_if(
          materials_.begin(), materials_.end(),
          [&](const FacetMaterialSettings& m) { return m.name == canopy.facet_disc_material; });
      if (found == materials_.end())
        throw input_error(file, "model \"" + name + "\" is of disc leaves of the material \"" +
                                    canopy.facet_disc_material +
                                    "\" (canopy.facets.disc_material), which "
                                    "canopy.facets.materials does not give");
      models_.push_back(std::make_shared<const FacetModel>(
          std::move(discs), static_cast<int>(found - materials_.begin())));
      names.push_back(name);
      continue;
    }
    FacetMesh mesh = read_facet_mesh(file, name);
    // Each mesh material is one of the configuration's, by name.
    std::vector<int> numbers;
    for (const std::string& material : mesh.material_names) {
      const auto found =
          std::find_if(materials_.begin(), materials_.end(),
                       [&](const FacetMaterialSettings& m) { return m.name == material; });
      // Assimp names a mesh without a material DefaultMaterial, and a material whose name it
      // cannot hold (aiString's 1,023 bytes) too: the user never wrote that name.
      const std::string why =
          material == "DefaultMaterial" || material.empty()
              ? " (Assimp's name for a mesh with no material, or with one whose name is longer "
                "than the 1,023 bytes Assimp holds: give the mesh's materials short names, or "
                "give DefaultMaterial)"
              : "";
      if (found == materials_.end())
        throw input_error(file, "model \"" + name + "\" has the material \"" + material +
                                    "\", which canopy.facets.materials does not give" + why);
      numbers.push_back(static_cast<int>(found - materials_.begin()));
    }
    std::vector<int> triangle_materials(mesh.materials.size());
    for (std::size_t t = 0; t < mesh.materials.size(); ++t)
      triangle_materials[t] = numbers[mesh.materials[t]];
    models_.push_back(
        std::make_shared<const FacetModel>(std::move(mesh), std::move(triangle_materials)));
    names.push_back(name);
  }
  trees_ = read_facet_trees(canopy.facet_trees_file, names, settings.plane);
}

RegionVegetation FacetSource::grow(const VegetationRegion& region) const {
  RegionVegetation grown;
  Vegetation& geometry = grown.geometry;
  geometry.trunks.max_height_m = -std::numeric_limits<double>::infinity();
  const Geodetic centre = region.frame.origin();
  // A first cut in degrees, generous, before the frame's exact transform.
  const double metres_per_deg_lat = 111.0e3;
  const double metres_per_deg_lon =
      std::max(1.0, metres_per_deg_lat * std::cos(centre.lat_deg * std::numbers::pi / 180.0));
  for (const FacetTree& tree : trees_) {
    const FacetModel& model = *models_[tree.model];
    const double reach_m = region.half_size_m + tree.scale * model.reach_m();
    double lon_offset = std::remainder(tree.lon_deg - centre.lon_deg, 360.0);
    if (std::abs(tree.lat_deg - centre.lat_deg) * metres_per_deg_lat > 1.5 * reach_m + 10.0 ||
        std::abs(lon_offset) * metres_per_deg_lon > 1.5 * reach_m + 10.0)
      continue;
    const double ground_m = region.terrain.height_m(tree.lat_deg, tree.lon_deg);
    if (!std::isfinite(ground_m)) continue;
    const Vec3 foot = region.frame.to_local({tree.lat_deg, tree.lon_deg, ground_m + tree.z_m});
    if (std::abs(foot[0]) > reach_m || std::abs(foot[1]) > reach_m) continue;
    geometry.facets.push_back(
        {models_[tree.model], foot, tree.rotation_deg * std::numbers::pi / 180.0, tree.scale});
  }
  for (const FacetMaterialSettings& material : materials_) {
    Foliage optics;
    optics.reflectance.assign(material.reflectance.begin(),
                              material.reflectance.begin() + region.bands);
    optics.transmittance.assign(material.transmittance.begin(),
                                material.transmittance.begin() + region.bands);
    optics.trunk_reflectance = optics.reflectance;
    optics.leaf_angles = &leaf_angles_;
    grown.materials.push_back(std::move(optics));
    geometry.leaf_materials.push_back(material.leaf ? 1 : 0);
  }
  return grown;
}

VegetationTruth FacetSource::truth(const Scene& scene, const BeamSpot& spot,
                                   const std::vector<double>& /*nadir_projection*/) const {
  return measure_facets(scene, spot);
}

std::vector<VegetationSource::Placed> FacetSource::placed() const {
  std::vector<Placed> trees;
  for (const FacetTree& tree : trees_)
    trees.push_back({tree.lat_deg, tree.lon_deg, tree.scale * models_[tree.model]->reach_m()});
  return trees;
}

double FacetSource::region_bytes(const VegetationSettings&, double side_m) {
  return side_m * side_m / 20.0 * 256.0;
}

double FacetSource::source_bytes(const VegetationSettings& settings) {
  double bytes = 0.0;
  for (const auto& [name, file] : settings.canopy.facet_models) {
    std::error_code error;
    const std::uintmax_t size = std::filesystem::file_size(file, error);
    if (!error)
      bytes += (is_disc_leaf_file(file) ? disc_model_bytes_per_file_byte
                                        : facet_model_bytes_per_file_byte) *
               static_cast<double>(size);
  }
  return bytes;
}

namespace {
const VegetationRegistration facets(
    "facets", 3, {"facet trees", {.keys = VegetationTraits::Keys::facets}},
    {[](const VegetationSettings& s) { return std::make_unique<FacetSource>(s); },
     &FacetSource::region_bytes, &FacetSource::source_bytes, "/canopy/facets/models"});
}  // namespace

}  // namespace glaswave
