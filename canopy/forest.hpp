// Everything that grows in a run's scene: the canopy of the configuration, the stands whose
// polygons override it, and explicit crowns from a crowns file. Each kind of foliage has its
// own trees and optics; a shot asks for the trees near it.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <vector>

#include "canopy/leaf_angles.hpp"
#include "canopy/stand.hpp"
#include "canopy/stand_index.hpp"
#include "terrain/terrain_settings.hpp"

namespace glaswave {

class Forest {
 public:
  // Kind 0 is the configuration's canopy (its crowns_file, when given, replaces its random
  // trees); kind k > 0 is stand area k - 1.
  Forest(const CanopySettings& canopy, std::uint64_t seed,
         const std::optional<PlaneSettings>& plane);

  std::size_t kinds() const { return kinds_.size(); }
  const CanopySettings& canopy(int kind) const { return kinds_[kind].settings; }
  // Kinds with the same leaf angle distribution share one (the same object).
  const LeafAngles& leaf_angles(int kind) const { return *kinds_[kind].leaf_angles; }
  // Plant area per unit crown volume of a kind's crowns.
  double area_density_m2_m3(int kind) const { return kinds_[kind].area_density_m2_m3; }

  // The kind of canopy at a point: the stand whose polygons hold it, else 0 (through the
  // stands' spatial index: thousands of stands cost about what one does).
  int kind_at(double lat_deg, double lon_deg) const;

  // The crowns of the crowns file (empty without one).
  const std::vector<Tree>& explicit_trees() const { return kinds_.front().explicit_trees; }

  // Trees whose stems stand within `radius_m` of a point (a few more may come back).
  std::vector<Tree> trees_near(double lat_deg, double lon_deg, double radius_m) const;

 private:
  struct Kind {
    CanopySettings settings;
    std::shared_ptr<const LeafAngles> leaf_angles;
    std::optional<Stand> stand;        // random trees
    std::vector<Tree> explicit_trees;  // from a crowns file
    double area_density_m2_m3 = 0.0;
  };
  std::vector<Kind> kinds_;
  std::shared_ptr<const StandIndex> areas_;  // shared by copies of the forest
};

// Reads a crowns file: CSV with a header `lon,lat,base_m,radius_m,half_height_m` (degrees) or
// `x,y,base_m,radius_m,half_height_m` (metres east and north of the plane terrain's origin).
// Errors name the file and line (exit status 3).
std::vector<Tree> read_crowns_file(const std::filesystem::path& file,
                                   const std::optional<PlaneSettings>& plane);

}  // namespace glaswave
