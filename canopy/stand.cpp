// Deterministic random stands, tile by tile.
#include "canopy/stand.hpp"

#include <GeographicLib/Constants.hpp>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <pcg_random.hpp>

#include "canopy/crown.hpp"
#include "core/bit_mix.hpp"
#include "core/error.hpp"

namespace glaswave {
namespace {

constexpr double pi = std::numbers::pi;
constexpr double tile_m = 50.0;
constexpr double metres_per_degree = metres_per_degree_latitude;

constexpr auto mix = mix_bits;

double uniform(pcg32& engine) {
  // Two draws in a fixed order (the order of operands in one expression is unspecified).
  const std::uint32_t high = engine(), low = engine();
  return (static_cast<double>(high >> 5) * 67108864.0 + (low >> 6)) * 0x1.0p-53;
}

// A Poisson count by inversion, in chunks of mean at most 500 so that exp(-mean) never
// underflows (a sum of Poisson counts is a Poisson count of the summed mean).
std::int64_t poisson(pcg32& engine, double mean) {
  std::int64_t count = 0;
  while (mean > 0.0) {
    const double chunk = std::min(mean, 500.0);
    mean -= chunk;
    double term = std::exp(-chunk), cumulative = term;
    const double u = uniform(engine);
    std::int64_t k = 0;
    while (u > cumulative && term > 0.0) {
      ++k;
      term *= chunk / static_cast<double>(k);
      cumulative += term;
    }
    count += k;
  }
  return count;
}

}  // namespace

Stand::Stand(const CanopySettings& canopy, std::uint64_t seed) : canopy_(canopy), seed_(seed) {
  const double crown_area_m2 = pi * canopy.crown_radius_m * canopy.crown_radius_m;
  // The configuration keeps cover below 1 for random crowns; a closed canopy is a layer.
  trees_per_m2_ = -std::log1p(-canopy.cover) / crown_area_m2;
  const double volume_m3 =
      crown_volume_m3(canopy.crown_shape, canopy.crown_radius_m, canopy.crown_half_height_m);
  area_density_m2_m3_ = trees_per_m2_ > 0.0 ? canopy.pai / (trees_per_m2_ * volume_m3) : 0.0;
}

std::vector<Tree> Stand::trees_near(double lat_deg, double lon_deg, double radius_m) const {
  std::vector<Tree> trees;
  if (trees_per_m2_ <= 0.0) return trees;
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
    // The tile's true area, from the ellipsoid's radii of curvature at its centre.
    const double s2 = std::sin(row_lat_deg * deg) * std::sin(row_lat_deg * deg);
    const double a_m = GeographicLib::Constants::WGS84_a();
    const double e2 =
        GeographicLib::Constants::WGS84_f() * (2.0 - GeographicLib::Constants::WGS84_f());
    const double meridian_m = a_m * (1.0 - e2) / std::pow(1.0 - e2 * s2, 1.5);
    const double normal_m = a_m / std::sqrt(1.0 - e2 * s2);
    const double tile_area_m2 =
        meridian_m * tile_lat_deg * deg * normal_m * cos_lat * tile_lon_deg * deg;
    const auto col_first =
        static_cast<std::int64_t>(std::floor((lon_deg - reach_lon_deg) / tile_lon_deg));
    const auto col_last =
        static_cast<std::int64_t>(std::floor((lon_deg + reach_lon_deg) / tile_lon_deg));
    for (std::int64_t col = col_first; col <= col_last; ++col) {
      pcg32 engine(mix(seed_ ^ mix(static_cast<std::uint64_t>(row))),
                   mix(static_cast<std::uint64_t>(col) + seed_));
      const std::int64_t count = poisson(engine, trees_per_m2_ * tile_area_m2);
      for (std::int64_t i = 0; i < count; ++i) {
        Tree tree;
        tree.lat_deg = (row + uniform(engine)) * tile_lat_deg;
        tree.lon_deg = (col + uniform(engine)) * tile_lon_deg;
        tree.crown_base_m = canopy_.crown_base_m[0] +
                            uniform(engine) * (canopy_.crown_base_m[1] - canopy_.crown_base_m[0]);
        tree.crown_radius_m = canopy_.crown_radius_m;
        tree.crown_half_height_m = canopy_.crown_half_height_m;
        trees.push_back(tree);
      }
    }
  }
  return trees;
}

}  // namespace glaswave
