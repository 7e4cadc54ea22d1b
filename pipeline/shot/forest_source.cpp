// Crowns, trunks and layers of the forest placed in a shot's frame.
#include "pipeline/shot/forest_source.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace glaswave {
namespace {

constexpr int trunk_sides = 8;

// A vertical prism of `trunk_sides` faces from the ground to the crown base: a grid of
// (trunk_sides + 1) x 2 nodes around it (the last column the first's vertices again), each face
// the two triangles triangulate_grid makes of its cell; one material a trunk.
void add_trunk(Vegetation& vegetation, const Vec3& foot, double top_m, double radius_m,
               int material) {
  GroundMesh& mesh = vegetation.trunks;
  const auto first = static_cast<std::uint32_t>(mesh.vertices_m.size() / 3);
  for (int k = 0; k < trunk_sides; ++k) {
    const double angle = 2.0 * std::numbers::pi * k / trunk_sides;
    const double x = foot[0] + radius_m * std::cos(angle), y = foot[1] + radius_m * std::sin(angle);
    // The foot goes a little below the ground so that no gap shows on slopes.
    for (double z : {foot[2] - radius_m, top_m}) {
      mesh.vertices_m.insert(mesh.vertices_m.end(),
                             {static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)});
    }
  }
  MeshGrid grid;
  grid.width = trunk_sides + 1;
  grid.height = 2;
  for (std::uint32_t level = 0; level < 2; ++level)
    for (int k = 0; k <= trunk_sides; ++k)
      grid.nodes.push_back(first + 2 * static_cast<std::uint32_t>(k % trunk_sides) + level);
  mesh.grids.push_back(std::move(grid));
  vegetation.trunk_materials.push_back(material);
  mesh.max_height_m = std::max(mesh.max_height_m, top_m);
}

// The homogeneous layer over the footprint's mean ground (the RAMI HOM case); none at PAI 0.
Vegetation layer_vegetation(const Forest& forest, const SurfaceOrientation& ground) {
  Vegetation vegetation;
  vegetation.trunks.max_height_m = -std::numeric_limits<double>::infinity();
  const CanopySettings& canopy = forest.canopy(0);
  if (canopy.pai <= 0.0) return vegetation;
  const double deg = std::numbers::pi / 180.0;
  const double fall = std::tan(ground.slope_deg * deg);
  TurbidLayer layer;
  layer.ground_slope_x = -fall * std::sin(ground.aspect_deg * deg);
  layer.ground_slope_y = -fall * std::cos(ground.aspect_deg * deg);
  layer.bottom_m = canopy.crown_base_m[0];
  layer.top_m = canopy.crown_base_m[0] + 2.0 * canopy.crown_half_height_m;
  layer.area_density_m2_m3 = forest.area_density_m2_m3(0);
  vegetation.layer = layer;
  return vegetation;
}

// The trees whose crowns reach into the region, each on the terrain under its stem; crowns and
// trunks tagged with their kind.
Vegetation crowns_vegetation(const Forest& forest, const VegetationRegion& region) {
  Vegetation vegetation;
  vegetation.trunks.max_height_m = -std::numeric_limits<double>::infinity();
  const Geodetic centre = region.frame.origin();
  double widest_m = 0.0;
  for (std::size_t k = 0; k < forest.kinds(); ++k)
    widest_m = std::max(widest_m, forest.canopy(k).crown_radius_m);
  for (const Tree& tree : forest.trees_near(centre.lat_deg, centre.lon_deg,
                                            region.half_size_m * std::sqrt(2.0) + widest_m)) {
    const CanopySettings& canopy = forest.canopy(tree.kind);
    if (canopy.pai <= 0.0) continue;
    // A strip leaves out most of its square: the trees far outside it (placed at the frame's
    // height, a few centimetres from where their ground puts them) skip the terrain's lookup.
    if (region.strip) {
      const Vec3 near = region.frame.to_local({tree.lat_deg, tree.lon_deg, centre.h_m});
      if (!region.strip->holds(near[0], near[1], tree.crown_radius_m + 5.0)) continue;
    }
    const double ground_m = region.terrain.height_m(tree.lat_deg, tree.lon_deg);
    if (!std::isfinite(ground_m)) continue;
    const Vec3 foot = region.frame.to_local({tree.lat_deg, tree.lon_deg, ground_m});
    const double reach_m = region.half_size_m + tree.crown_radius_m;
    if (std::abs(foot[0]) > reach_m || std::abs(foot[1]) > reach_m) continue;
    if (region.strip && !region.strip->holds(foot[0], foot[1], tree.crown_radius_m)) continue;
    Crown crown;
    crown.shape = canopy.crown_shape;
    crown.base_m = foot + Vec3{0.0, 0.0, tree.crown_base_m};
    crown.radius_m = tree.crown_radius_m;
    crown.half_height_m = tree.crown_half_height_m;
    crown.area_density_m2_m3 = tree.area_density_m2_m3 > 0.0 ? tree.area_density_m2_m3
                                                             : forest.area_density_m2_m3(tree.kind);
    crown.material = tree.kind;
    vegetation.crowns.push_back(crown);
    if (canopy.dbh_m > 0.0 && tree.crown_base_m > 0.0)
      add_trunk(vegetation, foot, crown.base_m[2], 0.5 * canopy.dbh_m, tree.kind);
  }
  return vegetation;
}

// Renumbers the geometry's kinds to `local` (by kind; -1 for a kind it does not hold).
void renumber(Vegetation& vegetation, const std::vector<int>& local) {
  for (Crown& crown : vegetation.crowns) crown.material = local[crown.material];
  for (int& material : vegetation.trunk_materials) material = local[material];
  if (vegetation.layer) vegetation.layer->material = local[vegetation.layer->material];
}

// Whether the two scatter alike: kinds that differ only in their structure (a stand's PAI or
// cover) share one material, and a free path projects one G for both.
bool same_optics(const Foliage& a, const Foliage& b) {
  return a.reflectance == b.reflectance && a.transmittance == b.transmittance &&
         a.trunk_reflectance == b.trunk_reflectance && a.leaf_angles == b.leaf_angles &&
         a.leaf_size_m == b.leaf_size_m;
}

double tree_density_m2(const CanopySettings& canopy) {
  if (canopy.crown_shape == CrownShape::layer || !canopy.crowns_file.empty()) return 0.0;
  return -std::log1p(-canopy.cover) /
         (std::numbers::pi * canopy.crown_radius_m * canopy.crown_radius_m);
}

}  // namespace

ForestSource::ForestSource(const VegetationSettings& settings)
    : forest_(settings.canopy, settings.seed, settings.plane) {}

RegionVegetation ForestSource::grow(const VegetationRegion& region) const {
  RegionVegetation grown;
  grown.geometry = forest_.canopy(0).crown_shape == CrownShape::layer
                       ? layer_vegetation(forest_, region.ground)
                       : crowns_vegetation(forest_, region);
  // The kinds the region holds, in the forest's order, each given the first material that
  // scatters as it does.
  const Vegetation& geometry = grown.geometry;
  std::vector<int> local(forest_.kinds(), -1);
  for (const Crown& crown : geometry.crowns) local[crown.material] = 0;
  for (int material : geometry.trunk_materials) local[material] = 0;
  if (geometry.layer) local[geometry.layer->material] = 0;
  for (std::size_t kind = 0; kind < local.size(); ++kind) {
    if (local[kind] < 0) continue;
    Foliage optics = material(static_cast<int>(kind), region.bands);
    const auto same = std::find_if(grown.materials.begin(), grown.materials.end(),
                                   [&](const Foliage& m) { return same_optics(m, optics); });
    local[kind] = static_cast<int>(same - grown.materials.begin());
    if (same == grown.materials.end()) grown.materials.push_back(std::move(optics));
  }
  renumber(grown.geometry, local);
  return grown;
}

// Plant-area weighted elements: leaves bi-Lambertian, bark inside crowns Lambertian and opaque.
Foliage ForestSource::material(int kind, std::size_t bands) const {
  const CanopySettings& canopy = forest_.canopy(kind);
  Foliage foliage;
  for (std::size_t band = 0; band < bands; ++band) {
    foliage.reflectance.push_back(canopy.green_fraction * canopy.leaf_reflectance[band] +
                                  canopy.bark_fraction * canopy.bark_reflectance[band]);
    foliage.transmittance.push_back(canopy.green_fraction * canopy.leaf_transmittance[band]);
  }
  foliage.trunk_reflectance = canopy.bark_reflectance;
  foliage.leaf_angles = &forest_.leaf_angles(kind);
  foliage.leaf_size_m = canopy.leaf_size_m;
  return foliage;
}

double ForestSource::region_bytes(const VegetationSettings& settings, double side_m) {
  double density = tree_density_m2(settings.canopy);
  for (const StandArea& stand : settings.canopy.stand_areas)
    density = std::max(density, tree_density_m2(stand.canopy));
  return density * side_m * side_m * forest_tree_bytes;
}

namespace {
const VegetationRegistration forest(
    "forest", 0, {"crowns, stands and a layer", {.keys = VegetationTraits::Keys::crowns}},
    {[](const VegetationSettings& s) { return std::make_unique<ForestSource>(s); },
     &ForestSource::region_bytes, nullptr, "/canopy/crown_radius_m", forest_tree_bytes});
}  // namespace

}  // namespace glaswave
