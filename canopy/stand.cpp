// Deterministic random stands, tile by tile.
#include "canopy/stand.hpp"

#include <GeographicLib/Constants.hpp>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "canopy/crown.hpp"
#include "core/random.hpp"
#include "core/samplers.hpp"

namespace glaswave {
namespace {

constexpr double pi = std::numbers::pi;
constexpr double tile_m = 50.0;
constexpr double metres_per_degree = metres_per_degree_latitude;

// The true area of a tile of the given sides whose centre is at `lat_deg`, from the ellipsoid's
// radii of curvature there.
double tile_area_m2(double lat_deg, double tile_lat_deg, double tile_lon_deg) {
  const double deg = pi / 180.0;
  const double s2 = std::sin(lat_deg * deg) * std::sin(lat_deg * deg);
  const double a_m = GeographicLib::Constants::WGS84_a();
  const double e2 =
      GeographicLib::Constants::WGS84_f() * (2.0 - GeographicLib::Constants::WGS84_f());
  const double meridian_m = a_m * (1.0 - e2) / std::pow(1.0 - e2 * s2, 1.5);
  const double normal_m = a_m / std::sqrt(1.0 - e2 * s2);
  return meridian_m * tile_lat_deg * deg * normal_m * std::cos(lat_deg * deg) * tile_lon_deg * deg;
}

}  // namespace

Stand::Stand(const CanopySettings& canopy, std::uint64_t seed, std::uint64_t kind)
    : canopy_(canopy), seed_(seed), kind_(kind) {
  const double crown_area_m2 = pi * canopy.crown_radius_m * canopy.crown_radius_m;
  // The configuration keeps cover below 1 for random crowns; a closed canopy is a layer.
  trees_per_m2_ = -std::log1p(-canopy.cover) / crown_area_m2;
  const double volume_m3 =
      crown_volume_m3(canopy.crown_shape, canopy.crown_radius_m, canopy.crown_half_height_m);
  area_density_m2_m3_ = trees_per_m2_ > 0.0 ? canopy.pai / (trees_per_m2_ * volume_m3) : 0.0;
}

namespace {

// Calls visit(row, col, tile_lat_deg, tile_lon_deg, row_lat_deg) for the tiles within reach of a
// point: a tile is about tile_m square, rows of tiles narrower in longitude towards the poles.
template <typename Visit>
void for_each_tile_near(double lat_deg, double lon_deg, double radius_m, Visit visit) {
  const double deg = pi / 180.0;
  const double tile_lat_deg = tile_m / metres_per_degree;
  const double reach_lat_deg = radius_m / metres_per_degree + tile_lat_deg;
  const auto row_first =
      static_cast<std::int64_t>(std::floor((lat_deg - reach_lat_deg) / tile_lat_deg));
  const auto row_last =
      static_cast<std::int64_t>(std::floor((lat_deg + reach_lat_deg) / tile_lat_deg));
  for (std::int64_t row = row_first; row <= row_last; ++row) {
    const double row_lat_deg = (row + 0.5) * tile_lat_deg;
    const double cos_lat = std::max(std::cos(row_lat_deg * deg), 1e-3);
    const double tile_lon_deg = tile_lat_deg / cos_lat;
    const double reach_lon_deg = radius_m / (metres_per_degree * cos_lat) + tile_lon_deg;
    const auto col_first =
        static_cast<std::int64_t>(std::floor((lon_deg - reach_lon_deg) / tile_lon_deg));
    const auto col_last =
        static_cast<std::int64_t>(std::floor((lon_deg + reach_lon_deg) / tile_lon_deg));
    for (std::int64_t col = col_first; col <= col_last; ++col)
      visit(row, col, tile_lat_deg, tile_lon_deg, row_lat_deg);
  }
}

}  // namespace

TileBox stand_tiles_near(double lat_deg, double lon_deg, double radius_m) {
  TileBox box{INFINITY, INFINITY, -INFINITY, -INFINITY};
  for_each_tile_near(
      lat_deg, lon_deg, radius_m,
      [&](std::int64_t row, std::int64_t col, double tile_lat_deg, double tile_lon_deg, double) {
        // The corners as trees_near computes its trees' positions.
        box.lat0_deg = std::min(box.lat0_deg, (row + 0.0) * tile_lat_deg);
        box.lat1_deg = std::max(box.lat1_deg, (row + 1.0) * tile_lat_deg);
        box.lon0_deg = std::min(box.lon0_deg, (col + 0.0) * tile_lon_deg);
        box.lon1_deg = std::max(box.lon1_deg, (col + 1.0) * tile_lon_deg);
      });
  return box;
}

std::vector<Tree> Stand::trees_near(double lat_deg, double lon_deg, double radius_m,
                                    const TileBox* within) const {
  std::vector<Tree> trees;
  if (trees_per_m2_ <= 0.0) return trees;
  for_each_tile_near(
      lat_deg, lon_deg, radius_m,
      [&](std::int64_t row, std::int64_t col, double tile_lat_deg, double tile_lon_deg,
          double row_lat_deg) {
        // A tile's trees lie within its corners, computed as their positions are.
        if (within && ((row + 1.0) * tile_lat_deg < within->lat0_deg ||
                       (row + 0.0) * tile_lat_deg > within->lat1_deg ||
                       (col + 1.0) * tile_lon_deg < within->lon0_deg ||
                       (col + 0.0) * tile_lon_deg > within->lon1_deg))
          return;
        const double tile_area_m2 = glaswave::tile_area_m2(row_lat_deg, tile_lat_deg, tile_lon_deg);
        RandomStream random(seed_, pair_key(row, col), kind_, RandomPurpose::stand);
        const auto count = static_cast<std::int64_t>(poisson(random, trees_per_m2_ * tile_area_m2));
        for (std::int64_t i = 0; i < count; ++i) {
          Tree tree;
          tree.lat_deg = (row + random.uniform()) * tile_lat_deg;
          tree.lon_deg = (col + random.uniform()) * tile_lon_deg;
          tree.crown_base_m =
              canopy_.crown_base_m[0] +
              random.uniform() * (canopy_.crown_base_m[1] - canopy_.crown_base_m[0]);
          tree.crown_radius_m = canopy_.crown_radius_m;
          tree.crown_half_height_m = canopy_.crown_half_height_m;
          trees.push_back(tree);
        }
      });
  return trees;
}

}  // namespace glaswave
