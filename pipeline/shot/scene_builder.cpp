// Ground, vegetation and optics of one footprint's scene.
#include "pipeline/shot/scene_builder.hpp"

#include "terrain/ground_mesh.hpp"

namespace glaswave {

SceneBuilder::SceneBuilder(const Terrain& terrain, const RoughnessSettings& roughness,
                           std::uint64_t seed, std::vector<double> soil_reflectance,
                           const VegetationSource* vegetation, std::size_t bands)
    : terrain_(terrain),
      roughness_(std::make_unique<RoughnessField>(roughness, seed)),
      soil_reflectance_(std::move(soil_reflectance)),
      vegetation_(vegetation),
      bands_(bands) {}

SceneBuilder::~SceneBuilder() = default;

BuiltScene SceneBuilder::build(const LocalFrame& frame, const SurfaceOrientation& ground,
                               double half_size_m, double rough_half_size_m) const {
  // Roughness too fine to mesh under the beam is refused here, as a roughness setting.
  const GroundMesh mesh = build_ground_mesh(terrain_, frame, half_size_m, terrain_.detail_m(),
                                            roughness_.get(), rough_half_size_m);
  RegionVegetation grown;
  if (vegetation_) grown = vegetation_->grow({terrain_, frame, half_size_m, ground, bands_});
  BuiltScene built;
  built.optics.soil_reflectance = soil_reflectance_;
  built.optics.foliage = std::move(grown.materials);
  built.scene = std::make_unique<Scene>(device_, mesh, grown.geometry);
  return built;
}

}  // namespace glaswave
