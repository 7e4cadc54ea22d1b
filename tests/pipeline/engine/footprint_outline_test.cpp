// The footprint polygon of the products: the beam's 1/e^2 contour traced on the terrain. A
// narrow cone of half-angle alpha at slant range R cuts a surface in an ellipse 2 R alpha across
// the tilt and 2 R alpha / cos(i) along it, i the local incidence: from 600 km that is
// 2 H alpha / (cos(off-nadir) cos(i)) along, about 1/cos^2 of the nadir footprint on level ground.
#include <gtest/gtest.h>

#include <GeographicLib/LocalCartesian.hpp>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "footprints/track.hpp"
#include "pipeline/engine/inputs.hpp"
#include "tests/pipeline/engine/engine_test_support.hpp"

namespace glaswave {
namespace {

constexpr double deg = std::numbers::pi / 180.0;

struct Outline {
  double along_m, across_m, incidence_deg, range_m, angle_rad;
};

// One shot aimed at the plane's origin, tilted toward the east; its polygon measured on the
// plane: the longest chord (the ellipse's major axis) and the width north-south.
Outline outline(double off_nadir_deg, double slope_deg, double ifov_rad = 0.0004) {
  nlohmann::json document = test_support::plane_shot("glas", slope_deg, off_nadir_deg, 200);
  document["sensor"]["ifov_rad"] = ifov_rad;
  const Config config = parse_config(document);
  const auto terrain = make_terrain(config.terrain);
  const Footprint footprint = Track(config.track, *terrain).footprint(0);
  const std::unique_ptr<ShotSimulator> made = make_shot_simulator(config, *terrain);
  const ShotSimulator& simulator = *made;
  const ShotRecord record = simulator.simulate(footprint);
  EXPECT_GE(record.footprint_lonlat.size(), 30u);

  const GeographicLib::LocalCartesian local(footprint.ground.lat_deg, footprint.ground.lon_deg,
                                            footprint.ground.h_m);
  std::vector<Vec3> points;
  for (const auto& [lon, lat] : record.footprint_lonlat) {
    Vec3 p{};
    local.Forward(lat, lon, terrain->height_m(lat, lon), p[0], p[1], p[2]);
    points.push_back(p);
  }
  Outline out{};
  double north_min = 1e9, north_max = -1e9;
  for (const Vec3& p : points) {
    for (const Vec3& q : points) out.along_m = std::max(out.along_m, norm(p - q));
    north_min = std::min(north_min, p[1]);
    north_max = std::max(north_max, p[1]);
  }
  out.across_m = north_max - north_min;
  // Incidence on the plane (facing east, tilted by the slope), the beam seen in the local frame.
  const Vec3 normal{std::sin(slope_deg * deg), 0.0, std::cos(slope_deg * deg)};
  const LocalFrame frame(footprint.ground);
  out.incidence_deg = std::acos(-dot(frame.local_direction(footprint.beam_ecef), normal)) / deg;
  out.range_m = footprint.range_m;
  // The 1/e^2 contour's half-angle: two sigma of the glas preset's beam (29.2 urad), unless the
  // field of view (its half-angle) is narrower: the receiver sees nothing beyond it.
  out.angle_rad = std::min(2.0 * 29.2e-6, 0.5 * ifov_rad);
  // Counter-clockwise in longitude and latitude.
  double twice_area = 0.0;
  for (std::size_t i = 0; i + 1 < record.footprint_lonlat.size(); ++i) {
    const auto& a = record.footprint_lonlat[i];
    const auto& b = record.footprint_lonlat[i + 1];
    twice_area += a[0] * b[1] - b[0] * a[1];
  }
  EXPECT_GT(twice_area, 0.0);
  return out;
}

TEST(FootprintOutline, OffNadirPolygonIsStretchedAlongTheTiltBy1OverCosIncidence) {
  const Outline nadir = outline(0.0, 0.0);
  EXPECT_NEAR(nadir.across_m / (2.0 * nadir.range_m * nadir.angle_rad), 1.0, 0.01);
  EXPECT_NEAR(nadir.along_m / nadir.across_m, 1.0, 0.01);
  EXPECT_NEAR(nadir.along_m, 70.0, 5.0);  // the glas beam

  // A field of view of 100 urad clips the beam: the outline is its edge, 50 urad, 60 m across.
  const Outline clipped = outline(0.0, 0.0, 100e-6);
  EXPECT_NEAR(clipped.across_m / (2.0 * clipped.range_m * 50e-6), 1.0, 0.01);
  EXPECT_NEAR(clipped.along_m / clipped.across_m, 1.0, 0.01);

  for (const double slope_deg : {0.0, 15.0}) {
    const Outline tilted = outline(30.0, slope_deg);
    // 30 deg off nadir from 600 km meets level ground at about 33 deg (the Earth curves away).
    EXPECT_NEAR(tilted.incidence_deg, 33.2 + slope_deg, 0.3) << slope_deg;
    const double cos_i = std::cos(tilted.incidence_deg * deg);
    EXPECT_NEAR(tilted.across_m / (2.0 * tilted.range_m * tilted.angle_rad), 1.0, 0.01)
        << slope_deg;
    EXPECT_NEAR(tilted.along_m * cos_i / tilted.across_m, 1.0, 0.01) << slope_deg;
    // Against the nadir footprint: (R / H) / cos(i), which is 1 / (cos(off-nadir) cos(i)), near
    // 1/cos^2 on level ground, but for the Earth's curvature (the range is 1.6 % longer here).
    EXPECT_NEAR(tilted.along_m / nadir.along_m * cos_i * nadir.range_m / tilted.range_m, 1.0, 0.01)
        << slope_deg;
    EXPECT_NEAR(tilted.along_m / nadir.along_m * std::cos(30.0 * deg) * cos_i, 1.0, 0.025)
        << slope_deg;
  }
}

// The outline is the footprint polygons' alone: a run that writes none (output.footprints false)
// leaves it empty and skips its ray queries, and every other field is the same bits.
TEST(FootprintOutline, LeftEmptyWhereNoFootprintPolygonIsWritten) {
  nlohmann::json document = test_support::plane_shot("north2010", 20.0, 0.0, 50);
  document["output"] = {{"netcdf", true}, {"footprints", true}};
  const Config with_polygons = parse_config(document);
  document["output"]["footprints"] = false;
  const Config without_polygons = parse_config(document);
  const auto terrain = make_terrain(with_polygons.terrain);
  const Footprint footprint = Track(with_polygons.track, *terrain).footprint(0);
  std::int64_t queries_with = 0, queries_without = 0;
  const ShotRecord a =
      make_run_shot_simulator(with_polygons, *terrain)->simulate(footprint, &queries_with);
  const ShotRecord b =
      make_run_shot_simulator(without_polygons, *terrain)->simulate(footprint, &queries_without);
  EXPECT_GE(a.footprint_lonlat.size(), 30u);
  EXPECT_TRUE(b.footprint_lonlat.empty());
  EXPECT_EQ(queries_with - queries_without, 36);
  EXPECT_EQ(a.rx_waveform_W, b.rx_waveform_W);
  EXPECT_EQ(a.rh_m, b.rh_m);
  EXPECT_EQ(a.slope_deg, b.slope_deg);
  EXPECT_EQ(a.solar_elevation_deg, b.solar_elevation_deg);
  EXPECT_EQ(a.cover_true, b.cover_true);
}

}  // namespace
}  // namespace glaswave
