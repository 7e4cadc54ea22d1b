// The one scene builder of a footprint, shared by the lidar shot and `glaswave brf`: the ground
// patch around the footprint (rough where the beam is), what the vegetation source grows on it,
// and the optics of what was built.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "pipeline/scene/scene.hpp"
#include "pipeline/shot/vegetation_source.hpp"
#include "pipeline/transport/scattering.hpp"
#include "terrain/roughness.hpp"
#include "terrain/terrain.hpp"

namespace glaswave {

// A scene with the optics its material numbers index.
struct BuiltScene {
  std::unique_ptr<Scene> scene;
  SceneOptics optics;
};

class SceneBuilder {
 public:
  // `vegetation` may be null (bare ground); it and `terrain` outlive the builder.
  SceneBuilder(const Terrain& terrain, const RoughnessSettings& roughness, std::uint64_t seed,
               std::vector<double> soil_reflectance, const VegetationSource* vegetation,
               std::size_t bands);
  ~SceneBuilder();

  // The ground within `half_size_m` of the frame's origin (east and north), its roughness
  // meshed within `rough_half_size_m`, and the vegetation grown over it on `ground` (the
  // footprint's mean ground). Thread-safe.
  BuiltScene build(const LocalFrame& frame, const SurfaceOrientation& ground, double half_size_m,
                   double rough_half_size_m) const;
  // A strip's scene (footprints along a track sharing one): the ground within `strip` (cut from
  // the square of half-width `half_size_m`, which holds it), its roughness meshed within
  // `rough` (one square a footprint's beam), the vegetation grown within the strip.
  BuiltScene build(const LocalFrame& frame, const SurfaceOrientation& ground, double half_size_m,
                   const RegionStrip& strip, const std::vector<RoughSquare>& rough) const;

  const Terrain& terrain() const { return terrain_; }
  const RoughnessField& roughness() const { return *roughness_; }
  const VegetationSource* vegetation() const { return vegetation_; }

 private:
  const Terrain& terrain_;
  // The same for every shot: made once (its lattices' kernels), not per shot.
  std::unique_ptr<RoughnessField> roughness_;
  std::vector<double> soil_reflectance_;
  const VegetationSource* vegetation_;
  std::size_t bands_;
  RayDevice device_;  // one Embree device for every scene
};

}  // namespace glaswave
