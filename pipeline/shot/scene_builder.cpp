// Ground, vegetation and optics of one footprint's scene.
#include "pipeline/shot/scene_builder.hpp"

#include <algorithm>
#include <array>
#include <limits>

#include "terrain/ground_mesh.hpp"

namespace glaswave {
namespace {

// The triangles of `mesh` that may reach into the strip: their centroid within their longest
// edge of it.
GroundMesh cut_to_strip(const GroundMesh& mesh, const RegionStrip& strip) {
  GroundMesh cut;
  cut.vertices_m = mesh.vertices_m;
  cut.min_height_m = std::numeric_limits<double>::infinity();
  cut.max_height_m = -std::numeric_limits<double>::infinity();
  for (std::size_t t = 0; t < mesh.triangles.size(); t += 3) {
    std::array<Vec3, 3> p;
    for (int k = 0; k < 3; ++k) {
      const std::size_t v = 3 * std::size_t{mesh.triangles[t + k]};
      p[k] = {mesh.vertices_m[v], mesh.vertices_m[v + 1], mesh.vertices_m[v + 2]};
    }
    const double edge_m = std::max({norm(p[1] - p[0]), norm(p[2] - p[1]), norm(p[0] - p[2])});
    const Vec3 centroid = (1.0 / 3.0) * (p[0] + p[1] + p[2]);
    if (!strip.holds(centroid[0], centroid[1], edge_m)) continue;
    cut.triangles.insert(cut.triangles.end(), mesh.triangles.begin() + t,
                         mesh.triangles.begin() + t + 3);
    for (const Vec3& q : p) {
      cut.min_height_m = std::min(cut.min_height_m, q[2]);
      cut.max_height_m = std::max(cut.max_height_m, q[2]);
    }
  }
  if (cut.triangles.empty()) cut.min_height_m = cut.max_height_m = 0.0;
  return cut;
}

}  // namespace

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

BuiltScene SceneBuilder::build(const LocalFrame& frame, const SurfaceOrientation& ground,
                               double half_size_m, const RegionStrip& strip,
                               const std::vector<RoughSquare>& rough) const {
  // The terrain's own mesh over the square, cut to the strip, then roughened under each beam.
  GroundMesh mesh =
      cut_to_strip(build_ground_mesh(terrain_, frame, half_size_m, terrain_.detail_m()), strip);
  if (roughness_->enabled()) mesh = roughness_->roughen(mesh, frame, rough, terrain_.detail_m());
  RegionVegetation grown;
  if (vegetation_)
    grown = vegetation_->grow({terrain_, frame, half_size_m, ground, bands_, &strip});
  BuiltScene built;
  built.optics.soil_reflectance = soil_reflectance_;
  built.optics.foliage = std::move(grown.materials);
  built.scene = std::make_unique<Scene>(device_, mesh, grown.geometry);
  return built;
}

}  // namespace glaswave
