// ATLAS's six ground tracks: the beams' names, spots and strengths as ATL03 labels them in both
// orientations; each beam's pass checked with GeographicLib's inverse problem, not the
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

// The ATL03 data dictionary's spot table (and icepyx's gt2spot since its fix of October 2023,
// icepyx#458): backward (sc_orient 0) gt1l ... gt3r are spots 1 ... 6, forward (sc_orient 1)
// 6 ... 1; the strong spots are 1, 3 and 5, so the left beams are strong backward and the right
// ones forward. Written here as the table, not from the code's rule.
struct SpotRow {
  const char* name;
  int backward_spot, forward_spot;
  bool backward_strong, forward_strong;
};
constexpr SpotRow spot_table[] = {
    {"gt1l", 1, 6, true, false}, {"gt1r", 2, 5, false, true}, {"gt2l", 3, 4, true, false},
    {"gt2r", 4, 3, false, true}, {"gt3l", 5, 2, true, false}, {"gt3r", 6, 1, false, true},
};

TEST(AtlasBeams, SpotsAndStrengthsOfBothOrientationsAsTheDataDictionaryGivesThem) {
  for (const AtlasOrientation orientation :
       {AtlasOrientation::backward, AtlasOrientation::forward}) {
    const bool backward = orientation == AtlasOrientation::backward;
    const auto& beams = atlas_beams(orientation);
    for (int i = 0; i < 6; ++i) {
      const SpotRow& row = spot_table[i];
      const int spot = backward ? row.backward_spot : row.forward_spot;
      const bool strong = backward ? row.backward_strong : row.forward_strong;
      EXPECT_EQ(beams[i].name, row.name);
      EXPECT_EQ(beams[i].spot_number, spot) << row.name;
      EXPECT_EQ(atlas_spot_number(row.name, orientation), spot) << row.name;
      EXPECT_EQ(beams[i].strong, strong) << row.name;
      EXPECT_NEAR(beams[i].energy_ratio, strong ? 1.0 : 45.0 / 175.0, 1e-12);
      EXPECT_EQ(beams[i].along_m, strong ? 0.0 : 2500.0) << row.name;
    }
  }
  // A real backward granule's gt1r is spot 2 (the check against real files).
  EXPECT_EQ(atlas_spot_number("gt1r", AtlasOrientation::backward), 2);
  EXPECT_EQ(atlas_orientation("forward"), AtlasOrientation::forward);
  EXPECT_EQ(atlas_orientation("backward"), AtlasOrientation::backward);
  EXPECT_THROW(atlas_orientation("sideways"), std::invalid_argument);
  EXPECT_THROW(atlas_spot_number("gt4l", AtlasOrientation::backward), std::invalid_argument);
}

TEST(AtlasBeams, GroundTracksKeepTheirPlacesInEitherOrientation) {
  // The ground tracks are numbered from the left of the direction of travel: turning the
  // spacecraft changes which spot lights them, not where they are.
  for (int i = 0; i < 6; ++i)
    EXPECT_EQ(atlas_beams(AtlasOrientation::forward)[i].across_m,
              atlas_beams(AtlasOrientation::backward)[i].across_m);
  const std::vector<AtlasBeam> chosen =
      select_atlas_beams({"gt2r", "gt1l"}, AtlasOrientation::forward);
  ASSERT_EQ(chosen.size(), 2u);
  EXPECT_EQ(chosen[0].name, "gt1l");
  EXPECT_EQ(chosen[0].spot_number, 6);
  EXPECT_EQ(chosen[1].spot_number, 3);
  EXPECT_TRUE(chosen[1].strong);
}

TEST(AtlasBeams, PairsAcrossTrack) {
  const auto& beams = atlas_beams();
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
