// A stand of trees placed at random at the target crown cover, deterministically by location:
// the ground is cut into tiles of about 50 m and each tile's trees come from a random stream
// keyed by (seed, tile, kind) (core/random.hpp), so the same tree is in the same place for every
// shot that sees it and a long track never builds the whole forest.
#pragma once

#include <cstdint>
#include <vector>

#include "canopy/canopy_settings.hpp"

namespace glaswave {

// Mean length of a degree of latitude along the meridian (m): tiles and search radii in degrees.
constexpr double metres_per_degree_latitude = 111132.954;

struct Tree {
  double lat_deg = 0.0;
  double lon_deg = 0.0;
  double crown_base_m = 0.0;  // height of the crown's bottom above the terrain under the stem
  double crown_radius_m = 0.0;
  double crown_half_height_m = 0.0;
  int kind = 0;  // which foliage it bears (Forest's kinds)
  // A crowns file's own leaf area: crown_lai (one-sided area over the crown's widest
  // cross-section, pi r^2), and the density it gives; 0: the kind's density (from `pai`).
  double crown_lai = 0.0;
  double area_density_m2_m3 = 0.0;
};

// A box in longitude and latitude (degrees).
struct TileBox {
  double lon0_deg, lat0_deg, lon1_deg, lat1_deg;
};

// The tiles Stand::trees_near visits for a point and radius: every tree it returns lies in them.
TileBox stand_tiles_near(double lat_deg, double lon_deg, double radius_m);

class Stand {
 public:
  // `kind` tells the stands of one run apart (Forest's kinds of canopy): each has its own trees.
  Stand(const CanopySettings& canopy, std::uint64_t seed, std::uint64_t kind = 0);

  // Trees whose stems stand within `radius_m` of a point (a few tiles more may come back); only
  // those of tiles that meet `within` when it is given (a stand's box: the same trees as without
  // it, less those that cannot be inside).
  std::vector<Tree> trees_near(double lat_deg, double lon_deg, double radius_m,
                               const TileBox* within = nullptr) const;

  // Poisson density that gives the crown cover: 1 - exp(-n pi r^2) = cover.
  double trees_per_m2() const { return trees_per_m2_; }
  // Plant area per unit crown volume that gives the scene's PAI.
  double area_density_m2_m3() const { return area_density_m2_m3_; }

 private:
  CanopySettings canopy_;
  std::uint64_t seed_;
  std::uint64_t kind_;
  double trees_per_m2_;
  double area_density_m2_m3_;
};

}  // namespace glaswave
