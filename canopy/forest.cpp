// The forest of a run: stands, stand polygons and explicit crowns.
#include "canopy/forest.hpp"

#include <GeographicLib/LocalCartesian.hpp>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <string>

#include "canopy/crown.hpp"
#include "core/csv.hpp"
#include "core/error.hpp"

namespace glaswave {
namespace {

constexpr double metres_per_degree = metres_per_degree_latitude;  // ample for a search radius

}  // namespace

Forest::Forest(const CanopySettings& canopy, std::uint64_t seed,
               const std::optional<PlaneSettings>& plane)
    : areas_(std::make_shared<StandIndex>(canopy.stand_areas)) {
  std::vector<const CanopySettings*> settings{&canopy};
  for (const StandArea& area : canopy.stand_areas) settings.push_back(&area.canopy);
  // Tabulating a distribution takes milliseconds: thousands of stands share a few.
  std::map<std::pair<LeafAngleDistribution, double>, std::shared_ptr<const LeafAngles>> tables;
  for (std::size_t k = 0; k < settings.size(); ++k) {
    const CanopySettings& s = *settings[k];
    auto& table = tables[{s.lad, s.lad_mean_deg}];
    if (!table) table = std::make_shared<const LeafAngles>(s.lad, s.lad_mean_deg);
    Kind kind{s, table, std::nullopt, {}, 0.0};
    kind.settings.stand_areas.clear();
    if (s.crown_shape == CrownShape::layer) {
      if (!canopy.stand_areas.empty())
        throw setting_error(ErrorKind::config, "crown_shape",
                            "a layer covers the whole scene: it cannot be used with stands");
      kind.area_density_m2_m3 = s.pai / (2.0 * s.crown_half_height_m);
    } else if (k == 0 && !s.crowns_file.empty()) {
      kind.explicit_trees = read_crowns_file(s.crowns_file, plane);
      // PAI is per unit ground area of the scene: here the crowns' bounding box.
      double crown_volume_m3 = 0.0, lat_min = 90, lat_max = -90, lon_min = 360, lon_max = -360,
             radius_sum = 0;
      for (const Tree& t : kind.explicit_trees) {
        crown_volume_m3 +=
            glaswave::crown_volume_m3(s.crown_shape, t.crown_radius_m, t.crown_half_height_m);
        lat_min = std::min(lat_min, t.lat_deg);
        lat_max = std::max(lat_max, t.lat_deg);
        lon_min = std::min(lon_min, t.lon_deg);
        lon_max = std::max(lon_max, t.lon_deg);
        radius_sum += t.crown_radius_m;
      }
      const double mean_radius_m = radius_sum / kind.explicit_trees.size();
      const double lat_m = metres_per_degree,
                   lon_m = lat_m * std::cos(0.5 * (lat_min + lat_max) * std::numbers::pi / 180.0);
      const double area_m2 = ((lat_max - lat_min) * lat_m + 2.0 * mean_radius_m) *
                             ((lon_max - lon_min) * lon_m + 2.0 * mean_radius_m);
      kind.area_density_m2_m3 = s.pai * area_m2 / crown_volume_m3;
      // A crown with its own crown_lai holds that leaf area whatever `pai` says.
      for (Tree& t : kind.explicit_trees)
        if (t.crown_lai > 0.0)
          t.area_density_m2_m3 =
              t.crown_lai * std::numbers::pi * t.crown_radius_m * t.crown_radius_m /
              glaswave::crown_volume_m3(s.crown_shape, t.crown_radius_m, t.crown_half_height_m);
    } else {
      kind.stand.emplace(s, seed, k);
      kind.area_density_m2_m3 = kind.stand->area_density_m2_m3();
    }
    kinds_.push_back(std::move(kind));
  }
}

int Forest::kind_at(double lat_deg, double lon_deg) const {
  return areas_->area_at(lon_deg, lat_deg);
}

std::vector<Tree> Forest::trees_near(double lat_deg, double lon_deg, double radius_m) const {
  std::vector<Tree> trees;
  // A stand's trees come only from the tiles trees_near visits, and grow only inside its
  // polygons: stands whose boxes miss those tiles give none, and only those that meet them can
  // hold a tree (searched once, highest first as kind_at takes them).
  std::vector<bool> near(kinds_.size(), true);
  std::vector<int> meeting;
  if (areas_->size() > 0) {
    const TileBox box = stand_tiles_near(lat_deg, lon_deg, radius_m);
    std::fill(near.begin() + 1, near.end(), false);
    meeting = areas_->areas_meeting(box.lon0_deg, box.lat0_deg, box.lon1_deg, box.lat1_deg);
    for (int area : meeting) near[area + 1] = true;
    std::sort(meeting.begin(), meeting.end(), std::greater<>());
  }
  for (std::size_t k = 0; k < kinds_.size(); ++k) {
    const Kind& kind = kinds_[k];
    if (kind.settings.crown_shape == CrownShape::layer || !near[k]) continue;
    // A stand's trees only from the tiles that meet its box.
    const std::optional<TileBox> box =
        k > 0 ? std::optional<TileBox>(areas_->box(static_cast<int>(k) - 1)) : std::nullopt;
    std::vector<Tree> candidates =
        kind.stand ? kind.stand->trees_near(lat_deg, lon_deg, radius_m, box ? &*box : nullptr)
                   : std::vector<Tree>{};
    for (const Tree& tree : kind.explicit_trees) {
      const double north_m = (tree.lat_deg - lat_deg) * metres_per_degree;
      const double east_m = (tree.lon_deg - lon_deg) * metres_per_degree *
                            std::cos(lat_deg * std::numbers::pi / 180.0);
      if (std::hypot(north_m, east_m) <= radius_m + tree.crown_radius_m + 10.0)
        candidates.push_back(tree);
    }
    for (Tree& tree : candidates) {
      // A stand's trees grow inside its polygons only; the scene's canopy grows outside them.
      // Random trees lie in the tiles searched: kind_at's answer among the stands meeting them.
      if (kind.stand && areas_->area_at(tree.lon_deg, tree.lat_deg, meeting) != static_cast<int>(k))
        continue;
      tree.kind = static_cast<int>(k);
      trees.push_back(tree);
    }
  }
  return trees;
}

}  // namespace glaswave

namespace glaswave {
namespace {

const std::vector<std::string_view> geographic_header{"lon", "lat", "base_m", "radius_m",
                                                      "half_height_m"};
const std::vector<std::string_view> metric_header{"x", "y", "base_m", "radius_m", "half_height_m"};

// Bounds of a crowns file's values: beyond them a row is a mistake (1e308), not a tree.
constexpr double max_offset_m = 1.0e6;
constexpr double max_tree_m = 1000.0;

// A crown from a row of the crowns file: degrees, or metres about the plane's origin.
Tree read_crown(const CsvReader& csv, const std::vector<std::string_view>& fields,
                const std::optional<GeographicLib::LocalCartesian>& origin, std::size_t columns) {
  const std::string place = csv.place();
  if (fields.size() != columns)
    throw input_error(place, "expected " + std::to_string(columns) + " values, got " +
                                 std::to_string(fields.size()));
  const std::vector<std::string_view>& names = origin ? metric_header : geographic_header;
  double values[5];
  for (int i = 0; i < 5; ++i) values[i] = csv.number(fields[i], names[i]);
  Tree tree;
  if (!origin) {
    if (values[0] < -180.0 || values[0] > 360.0)
      throw input_error(place, "lon must be in [-180, 360]");
    if (values[1] < -90.0 || values[1] > 90.0) throw input_error(place, "lat must be in [-90, 90]");
    tree.lon_deg = values[0];
    tree.lat_deg = values[1];
  } else {
    // Metres about the plane's origin: a scene is at most a few kilometres across.
    for (int i = 0; i < 2; ++i)
      if (std::abs(values[i]) > max_offset_m)
        throw input_error(place, std::string(names[i]) + " must be within " +
                                     std::to_string(static_cast<int>(max_offset_m)) +
                                     " m of the plane's origin");
    double h = 0.0;
    origin->Reverse(values[0], values[1], 0.0, tree.lat_deg, tree.lon_deg, h);
  }
  if (values[2] < 0.0) throw input_error(place, "base_m must be >= 0");
  if (values[3] <= 0.0) throw input_error(place, "radius_m must be > 0");
  if (values[4] <= 0.0) throw input_error(place, "half_height_m must be > 0");
  for (int i = 2; i < 5; ++i)
    if (values[i] > max_tree_m)
      throw input_error(place, std::string(names[i]) +
                                   " must be <= " + std::to_string(static_cast<int>(max_tree_m)) +
                                   " m: no tree is that large");
  tree.crown_base_m = values[2];
  tree.crown_radius_m = values[3];
  tree.crown_half_height_m = values[4];
  if (columns == 6) {
    tree.crown_lai = csv.number(fields[5], "crown_lai");
    // A crown as dense as RAMI's spheres (LAI 5) or any forest's is far below 100.
    if (!(tree.crown_lai > 0.0 && tree.crown_lai <= 100.0))
      throw input_error(place, "crown_lai must be in (0, 100]");
  }
  return tree;
}

}  // namespace

std::vector<Tree> read_crowns_file(const std::filesystem::path& file,
                                   const std::optional<PlaneSettings>& plane) {
  CsvReader csv(file, "the crowns file");
  std::vector<std::string_view> fields;
  std::optional<GeographicLib::LocalCartesian> origin;
  std::size_t columns = 5;
  // An optional last column, crown_lai: the crown's own leaf area.
  if (csv.next_row(fields) && fields.size() == 6 && fields[5] == "crown_lai") {
    columns = 6;
    fields.pop_back();
  }
  if (!fields.empty() && fields != geographic_header) {
    if (fields != metric_header)
      throw input_error(csv.place(),
                        "expected the header lon,lat,base_m,radius_m,half_height_m or "
                        "x,y,base_m,radius_m,half_height_m (and optionally crown_lai)");
    if (!plane)
      throw input_error(
          csv.place(),
          "x,y crowns are metres from terrain.plane's origin; with a DEM give lon,lat");
    origin.emplace(plane->origin_lat_deg, plane->origin_lon_deg, 0.0);
  }
  std::vector<Tree> trees;
  while (csv.next_row(fields)) trees.push_back(read_crown(csv, fields, origin, columns));
  if (trees.empty()) throw input_error(file.string(), "the crowns file lists no crowns");
  return trees;
}

}  // namespace glaswave
