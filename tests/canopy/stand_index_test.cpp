// The stands' spatial index against the plain rule (every stand, every edge): the same stand for
// every point, on edges and vertices too, for thousands of small stands and for one stand of
// 10^5 vertices; and a forest through the index grows the same trees as one without it.
#include "canopy/stand_index.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "canopy/forest.hpp"

namespace glaswave {
namespace {

using Ring = std::vector<std::array<double, 2>>;

Ring square(double lon_deg, double lat_deg, double side_deg) {
  return {{lon_deg, lat_deg},
          {lon_deg + side_deg, lat_deg},
          {lon_deg + side_deg, lat_deg + side_deg},
          {lon_deg, lat_deg + side_deg},
          {lon_deg, lat_deg}};
}

// A ragged star about (lon, lat): `vertices` points at radii drawn from [0.3, 1] x radius.
Ring star(double lon_deg, double lat_deg, double radius_deg, int vertices, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> r(0.3, 1.0);
  Ring ring;
  for (int k = 0; k < vertices; ++k) {
    const double t = 2.0 * std::numbers::pi * k / vertices, s = radius_deg * r(rng);
    ring.push_back({lon_deg + s * std::cos(t), lat_deg + s * std::sin(t)});
  }
  ring.push_back(ring.front());
  return ring;
}

// The plain rule: the last stand holding the point.
int plain_area_at(const std::vector<StandArea>& areas, double lon_deg, double lat_deg) {
  for (std::size_t k = areas.size(); k-- > 0;)
    if (inside_by_every_edge(areas[k], lon_deg, lat_deg)) return static_cast<int>(k + 1);
  return 0;
}

// 2000 squares of 0.0009 degrees (some overlapping, one with a hole, one a multipolygon) and one
// star of `star_vertices` over them.
std::vector<StandArea> many_stands(int star_vertices, std::mt19937_64& rng) {
  std::vector<StandArea> areas;
  std::uniform_real_distribution<double> jitter(0.0, 0.0004);
  for (int k = 0; k < 2000; ++k) {
    StandArea area;
    area.rings.push_back(square(7.0 + 0.001 * (k % 50) + jitter(rng),
                                45.0 + 0.001 * (k / 50) + jitter(rng), 0.0009));
    areas.push_back(area);
  }
  areas[10].rings.push_back(square(7.0103, 45.0003, 0.0002));  // a hole
  areas[20].rings.push_back(square(7.2, 45.2, 0.001));         // a second part
  areas.push_back(
      StandArea{{star(7.025, 45.02, 0.015, star_vertices, rng)}, {}});  // over the others
  return areas;
}

TEST(StandIndex, SameStandAsThePlainRuleEverywhere) {
  std::mt19937_64 rng(3);
  const std::vector<StandArea> areas = many_stands(100000, rng);
  const StandIndex index(areas);
  std::uniform_real_distribution<double> lon(6.99, 7.06), lat(44.99, 45.05);
  int in_stands = 0, in_star = 0;
  for (int k = 0; k < 1500; ++k) {
    const double x = lon(rng), y = lat(rng);
    const int expected = plain_area_at(areas, x, y);
    ASSERT_EQ(index.area_at(x, y), expected) << x << ", " << y;
    in_stands += expected > 0;
    in_star += expected == static_cast<int>(areas.size());
  }
  EXPECT_GT(in_stands, 500);
  EXPECT_GT(in_star, 50);
  // On vertices and at the middle of edges, where the rule's half-open tests decide.
  for (std::size_t a : {0, 10, 20, 333, 1999, 2000})  // a hole, two parts, the star
    for (const Ring& ring : areas[a].rings)
      for (std::size_t i = 1; i < ring.size(); i += std::max<std::size_t>(1, ring.size() / 50)) {
        const auto& p = ring[i - 1];
        const auto& q = ring[i];
        ASSERT_EQ(index.area_at(p[0], p[1]), plain_area_at(areas, p[0], p[1]));
        const double mx = 0.5 * (p[0] + q[0]), my = 0.5 * (p[1] + q[1]);
        ASSERT_EQ(index.area_at(mx, my), plain_area_at(areas, mx, my));
      }
  // Off every stand, and not a number.
  EXPECT_EQ(index.area_at(100.0, -30.0), 0);
  EXPECT_EQ(index.area_at(std::nan(""), 45.0), 0);
  EXPECT_EQ(StandIndex({}).area_at(7.0, 45.0), 0);
}

// A forest of 2001 stands with their own tree sizes: the trees near shots are exactly those of
// each stand's random trees kept by the plain rule (Forest::trees_near as it was before the index).
TEST(StandIndex, AForestGrowsTheSameTreesAsWithoutTheIndex) {
  std::mt19937_64 rng(5);
  CanopySettings canopy;
  canopy.cover = 0.5;
  canopy.crown_radius_m = 8.0;
  const CanopySettings stand_canopy = canopy;
  canopy.stand_areas = many_stands(10000, rng);
  for (std::size_t k = 0; k < canopy.stand_areas.size(); ++k) {
    canopy.stand_areas[k].canopy = stand_canopy;
    canopy.stand_areas[k].canopy.crown_radius_m = 6.0 + 0.001 * k;
  }
  const Forest forest(canopy, 9, std::nullopt);
  for (const auto& [lat, lon] :
       std::vector<std::array<double, 2>>{{45.0201, 7.0249}, {45.0004, 7.0102}, {44.99, 6.99}}) {
    std::vector<Tree> expected;
    for (std::size_t k = 0; k <= canopy.stand_areas.size(); ++k) {
      const CanopySettings& s = k == 0 ? canopy : canopy.stand_areas[k - 1].canopy;
      for (Tree tree : Stand(s, 9, k).trees_near(lat, lon, 60.0)) {
        // (Only a tree inside its own stand can have it as its last: tried first, for speed.)
        if (k > 0 && !inside_by_every_edge(canopy.stand_areas[k - 1], tree.lon_deg, tree.lat_deg))
          continue;
        if (plain_area_at(canopy.stand_areas, tree.lon_deg, tree.lat_deg) != static_cast<int>(k))
          continue;
        tree.kind = static_cast<int>(k);
        expected.push_back(tree);
      }
    }
    const std::vector<Tree> trees = forest.trees_near(lat, lon, 60.0);
    ASSERT_EQ(trees.size(), expected.size()) << lat << ", " << lon;
    EXPECT_GT(trees.size(), 20u);
    for (std::size_t t = 0; t < trees.size(); ++t) {
      EXPECT_EQ(trees[t].lat_deg, expected[t].lat_deg);
      EXPECT_EQ(trees[t].lon_deg, expected[t].lon_deg);
      EXPECT_EQ(trees[t].crown_base_m, expected[t].crown_base_m);
      EXPECT_EQ(trees[t].crown_radius_m, expected[t].crown_radius_m);
      EXPECT_EQ(trees[t].kind, expected[t].kind);
    }
  }
}

}  // namespace
}  // namespace glaswave
