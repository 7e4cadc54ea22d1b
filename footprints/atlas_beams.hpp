// ICESat-2's six ground tracks: ATLAS's beams in three pairs about the reference ground track
// (RGT), each pair 3.3 km from the next and its two beams 90 m apart across track and 2.5 km
// apart along it (Markus et al. 2017; Neumann et al. 2019), a strong and a weak beam in each.
// A beam's own pass is the reference pass moved by its offsets.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "footprints/track_settings.hpp"

namespace glaswave {

// The spacecraft's yaw, ATL03's orbit_info/sc_orient: ICESat-2 flies "backward" or "forward"
// and turns through 180 degrees about twice a year, which swaps which side of each pair of
// ground tracks the strong beam falls on.
enum class AtlasOrientation : int { backward = 0, forward = 1 };

struct AtlasBeam {
  std::string name;     // the product's group: gt1l, gt1r, ..., gt3r
  int spot_number = 0;  // ATLAS's laser spot, 1-6 (strong: 1, 3, 5)
  bool strong = false;
  double across_m = 0.0;      // right of the direction of travel (left beams negative)
  double along_m = 0.0;       // ahead of the reference ground track's shot
  double energy_ratio = 1.0;  // the beam's pulse energy over a strong beam's (45 / 175 weak)
};

// ATLAS's spot behind a ground track, as real ATL03 granules label it (the attribute
// atlas_spot_number; icepyx's gt2spot since its fix of October 2023): backward (sc_orient 0)
// gt1l ... gt3r are spots 1, 2, 3, 4, 5, 6, the left beam of each pair strong; forward
// (sc_orient 1) 6, 5, 4, 3, 2, 1, the right beam strong. The strong spots are 1, 3 and 5 in
// both. Throws std::invalid_argument for a name that is not a ground track.
int atlas_spot_number(const std::string& ground_track, AtlasOrientation orientation);

// The six beams with the spacecraft in `orientation`, gt1l to gt3r: their spots and strengths
// (atlas_spot_number). Pair centres at -3300, 0 and +3300 m across track, their beams 45 m
// either side, in either orientation (the ground tracks are numbered from the left of the
// direction of travel); the weak beam of each pair 2.5 km ahead of the strong one (the sign of
// that offset is a choice here).
const std::array<AtlasBeam, 6>& atlas_beams(
    AtlasOrientation orientation = AtlasOrientation::backward);

// The beams named in `names` (empty: all six), in atlas_beams()'s order. Throws
// std::invalid_argument naming an unknown beam or one named twice.
std::vector<AtlasBeam> select_atlas_beams(
    const std::vector<std::string>& names,
    AtlasOrientation orientation = AtlasOrientation::backward);

// "backward" or "forward" (the configuration's sensor.sc_orient) as an orientation; throws
// std::invalid_argument for other text.
AtlasOrientation atlas_orientation(const std::string& name);

// A `pass` track for one beam: the reference pass's start point moved `across_m` to the right
// of the heading and `along_m` along it, on the WGS84 geodesics (GeographicLib), the heading
// taken at the moved point; every other setting unchanged.
TrackSettings beam_pass(const TrackSettings& reference, const AtlasBeam& beam);

}  // namespace glaswave
