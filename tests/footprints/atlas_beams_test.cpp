// ATLAS's six ground tracks: the beams' names, spots and strengths as ATL03 labels them in the
// backward orientation; each beam's pass checked with GeographicLib's inverse problem, not the
// code's direct one: 90 m between the beams of a pair, 3.3 km between pairs, the weak beams
// 2.5 km ahead, and every beam's pass parallel to the reference one 10 km on.
#include "footprints/atlas_beams.hpp"

#include <gtest/gtest.h>

#include <GeographicLib/Geodesic.hpp>
#include <cmath>
#include <stdexcept>

namespace glaswave {
namespace {

const GeographicLib::Geodesic& wgs84() { return GeographicLib::Geodesic::WGS84(); }

double distance_m(double lat1, double lon1, double lat2, double lon2) {
  double s12 = 0.0;
  wgs84().Inverse(lat1, lon1, lat2, lon2, s12);
  return s12;
}

TEST(AtlasBeams, NamesSpotsAndStrengthsOfTheBackwardOrientation) {
  const auto& beams = atlas_beams();
  const char* names[] = {"gt1l", "gt1r", "gt2l", "gt2r", "gt3l", "gt3r"};
  // icepyx's gt2spot for sc_orient 0: the spots' order across the instrument turned about.
  const int spots[] = {5, 6, 3, 4, 1, 2};
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(beams[i].name, names[i]);
    EXPECT_EQ(beams[i].spot_number, spots[i]);
    EXPECT_EQ(beams[i].strong, i % 2 == 0);
    EXPECT_NEAR(beams[i].energy_ratio, i % 2 == 0 ? 1.0 : 45.0 / 175.0, 1e-12);
  }
  // Across track: the beams of a pair 90 m apart, the pairs' centres 3.3 km apart.
  for (int pair = 0; pair < 3; ++pair)
    EXPECT_NEAR(beams[2 * pair + 1].across_m - beams[2 * pair].across_m, 90.0, 1e-9);
  EXPECT_NEAR(beams[2].across_m - beams[0].across_m, 3300.0, 1e-9);
  EXPECT_NEAR(beams[4].across_m - beams[2].across_m, 3300.0, 1e-9);
  EXPECT_NEAR(beams[2].across_m + beams[3].across_m, 0.0, 1e-9);  // the central pair on the RGT
}

TEST(AtlasBeams, EachBeamsPassIsTheReferenceMovedByItsOffsets) {
  TrackSettings reference;
  reference.start_lat_deg = 60.0;
  reference.start_lon_deg = -45.0;
  reference.heading_deg = 350.0;
  for (const AtlasBeam& beam : atlas_beams()) {
    const TrackSettings pass = beam_pass(reference, beam);
    // Where the reference track is abreast of the beam's start, and its heading there.
    double lat_a = 0, lon_a = 0, heading_a = 0;
    wgs84().Direct(reference.start_lat_deg, reference.start_lon_deg, reference.heading_deg,
                   beam.along_m, lat_a, lon_a, heading_a);
    double s12 = 0, azimuth1 = 0, azimuth2 = 0;
    wgs84().Inverse(lat_a, lon_a, pass.start_lat_deg, pass.start_lon_deg, s12, azimuth1, azimuth2);
    EXPECT_NEAR(s12, std::abs(beam.across_m), 1e-3) << beam.name;
    // To the right of the heading for positive offsets, to the left for negative ones.
    const double side = std::remainder(azimuth1 - heading_a, 360.0);
    EXPECT_NEAR(side, beam.across_m > 0 ? 90.0 : -90.0, 1e-6) << beam.name;
    // Parallel: 10 km on, the two passes are still |across_m| apart (to 5 cm).
    double lat_r = 0, lon_r = 0, lat_b = 0, lon_b = 0, unused = 0;
    wgs84().Direct(lat_a, lon_a, heading_a, 10000.0, lat_r, lon_r, unused);
    wgs84().Direct(pass.start_lat_deg, pass.start_lon_deg, pass.heading_deg, 10000.0, lat_b, lon_b,
                   unused);
    EXPECT_NEAR(distance_m(lat_r, lon_r, lat_b, lon_b), std::abs(beam.across_m), 0.05) << beam.name;
    EXPECT_EQ(pass.altitude_m, reference.altitude_m);
    EXPECT_EQ(pass.shots, reference.shots);
  }
}

TEST(AtlasBeams, SelectionKeepsTheBeamsOrderAndRefusesUnknownOnes) {
  const std::vector<AtlasBeam> two = select_atlas_beams({"gt2r", "gt1l"});
  ASSERT_EQ(two.size(), 2u);
  EXPECT_EQ(two[0].name, "gt1l");
  EXPECT_EQ(two[1].name, "gt2r");
  EXPECT_EQ(select_atlas_beams({}).size(), 6u);
  EXPECT_THROW(select_atlas_beams({"gt4l"}), std::invalid_argument);
  EXPECT_THROW(select_atlas_beams({"gt1l", "gt1l"}), std::invalid_argument);
}

}  // namespace
}  // namespace glaswave
