// ATLAS's beam pattern and each beam's pass about the reference ground track.
#include "footprints/atlas_beams.hpp"

#include <GeographicLib/Geodesic.hpp>
#include <algorithm>
#include <stdexcept>

namespace glaswave {

namespace {

constexpr std::array<const char*, 6> ground_tracks = {"gt1l", "gt1r", "gt2l",
                                                      "gt2r", "gt3l", "gt3r"};

std::array<AtlasBeam, 6> make_beams(AtlasOrientation orientation) {
  constexpr double pair_m = 3300.0, half_pair_m = 45.0, weak_ahead_m = 2500.0;
  constexpr double weak = 45.0 / 175.0;
  std::array<AtlasBeam, 6> beams;
  for (std::size_t i = 0; i < beams.size(); ++i) {
    AtlasBeam& b = beams[i];
    b.name = ground_tracks[i];
    b.spot_number = atlas_spot_number(b.name, orientation);
    b.strong = b.spot_number % 2 == 1;
    const double pair_centre_m = (static_cast<double>(i / 2) - 1.0) * pair_m;
    b.across_m = pair_centre_m + (i % 2 == 0 ? -half_pair_m : half_pair_m);
    b.along_m = b.strong ? 0.0 : weak_ahead_m;
    b.energy_ratio = b.strong ? 1.0 : weak;
  }
  return beams;
}

}  // namespace

int atlas_spot_number(const std::string& ground_track, AtlasOrientation orientation) {
  const auto it = std::find(ground_tracks.begin(), ground_tracks.end(), ground_track);
  if (it == ground_tracks.end())
    throw std::invalid_argument("unknown beam \"" + ground_track +
                                "\"; the beams are gt1l, gt1r, gt2l, gt2r, gt3l, gt3r");
  const int backward = static_cast<int>(it - ground_tracks.begin()) + 1;
  return orientation == AtlasOrientation::backward ? backward : 7 - backward;
}

AtlasOrientation atlas_orientation(const std::string& name) {
  if (name == "backward") return AtlasOrientation::backward;
  if (name == "forward") return AtlasOrientation::forward;
  throw std::invalid_argument("unknown spacecraft orientation \"" + name +
                              "\"; it is \"backward\" or \"forward\"");
}

const std::array<AtlasBeam, 6>& atlas_beams(AtlasOrientation orientation) {
  static const std::array<AtlasBeam, 6> backward = make_beams(AtlasOrientation::backward);
  static const std::array<AtlasBeam, 6> forward = make_beams(AtlasOrientation::forward);
  return orientation == AtlasOrientation::forward ? forward : backward;
}

std::vector<AtlasBeam> select_atlas_beams(const std::vector<std::string>& names,
                                          AtlasOrientation orientation) {
  const std::array<AtlasBeam, 6>& all = atlas_beams(orientation);
  for (std::size_t i = 0; i < names.size(); ++i) {
    const auto known = std::find_if(all.begin(), all.end(),
                                    [&](const AtlasBeam& b) { return b.name == names[i]; });
    if (known == all.end())
      throw std::invalid_argument("unknown beam \"" + names[i] +
                                  "\"; the beams are gt1l, gt1r, gt2l, gt2r, gt3l, gt3r");
    if (std::find(names.begin(), names.begin() + static_cast<std::ptrdiff_t>(i), names[i]) !=
        names.begin() + static_cast<std::ptrdiff_t>(i))
      throw std::invalid_argument("beam \"" + names[i] + "\" named twice");
  }
  std::vector<AtlasBeam> chosen;
  for (const AtlasBeam& beam : all)
    if (names.empty() || std::find(names.begin(), names.end(), beam.name) != names.end())
      chosen.push_back(beam);
  return chosen;
}

TrackSettings beam_pass(const TrackSettings& reference, const AtlasBeam& beam) {
  const GeographicLib::Geodesic& wgs84 = GeographicLib::Geodesic::WGS84();
  TrackSettings moved = reference;
  double lat = reference.start_lat_deg, lon = reference.start_lon_deg;
  double heading = reference.heading_deg;
  if (beam.along_m != 0.0) {
    double lat2 = 0, lon2 = 0, azimuth2 = 0;
    wgs84.Direct(lat, lon, heading, beam.along_m, lat2, lon2, azimuth2);
    lat = lat2, lon = lon2, heading = azimuth2;
  }
  if (beam.across_m != 0.0) {
    double lat2 = 0, lon2 = 0, azimuth2 = 0;
    wgs84.Direct(lat, lon, heading + 90.0, beam.across_m, lat2, lon2, azimuth2);
    // The moved pass runs at right angles to the cross-track geodesic where it ends.
    heading = azimuth2 - 90.0;
    lat = lat2, lon = lon2;
  }
  moved.start_lat_deg = lat;
  moved.start_lon_deg = lon;
  moved.heading_deg = heading;
  return moved;
}

}  // namespace glaswave
