// The first vegetation source: today's Forest (canopy/forest.hpp) behind the VegetationSource
// interface, unchanged. Random crowns of the configuration's canopy (or a crowns file's), stands
// whose polygons override it, each crown on its bark-covered trunk standing on the terrain; or a
// homogeneous turbid layer following the footprint's mean ground. Registered as "forest".
#pragma once

#include "canopy/forest.hpp"
#include "pipeline/shot/vegetation_source.hpp"

namespace glaswave {

// What a tree takes in a shot's scene: its crown, its trunk's 16 triangles, Embree's copy and
// hierarchy of them. Measured: one shot's peak resident memory grows by 2.4 to 2.6 KiB a tree
// between 1 450 and 371 000 trees (glas preset, cover 0.7, crown radius 8, 1, 0.5 m).
inline constexpr double forest_tree_bytes = 2560.0;

class ForestSource : public VegetationSource {
 public:
  explicit ForestSource(const VegetationSettings& settings);

  // Crowns and trunks are tagged with their material: the region's kinds in the forest's order,
  // kinds that scatter alike (stands differing only in PAI or cover) sharing one.
  RegionVegetation grow(const VegetationRegion& region) const override;

  const Forest& forest() const { return forest_; }

  // Crowns stand where the forest placed them on the Earth; a layer follows the footprint's
  // mean ground.
  bool fixed_on_the_ground() const override {
    return forest_.canopy(0).crown_shape != CrownShape::layer;
  }

  bool grows_within_strips() const override { return true; }

  // The crowns file's crowns.
  std::vector<Placed> placed() const override {
    std::vector<Placed> crowns;
    for (const Tree& tree : forest_.explicit_trees())
      crowns.push_back({tree.lat_deg, tree.lon_deg, tree.crown_radius_m});
    return crowns;
  }

  // Randomly placed crowns of cover c and radius r are -ln(1 - c) / (pi r^2) a square metre (the
  // densest of the canopy's and its stands'); a layer or a crowns file has none at random.
  static double region_bytes(const VegetationSettings& settings, double side_m);

 private:
  Foliage material(int kind, std::size_t bands) const;

  Forest forest_;
};

}  // namespace glaswave
