// ATLAS's beam pattern and each beam's pass about the reference ground track.
#include "footprints/atlas_beams.hpp"

#include <GeographicLib/Geodesic.hpp>
#include <algorithm>
#include <stdexcept>

namespace glaswave {

const std::array<AtlasBeam, 6>& atlas_beams() {
  constexpr double pair_m = 3300.0, half_pair_m = 45.0, weak_ahead_m = 2500.0;
  constexpr double weak = 45.0 / 175.0;
  static const std::array<AtlasBeam, 6> beams = {{
      {"gt1l", 5, true, -pair_m - half_pair_m, 0.0, 1.0},
      {"gt1r", 6, false, -pair_m + half_pair_m, weak_ahead_m, weak},
      {"gt2l", 3, true, -half_pair_m, 0.0, 1.0},
      {"gt2r", 4, false, half_pair_m, weak_ahead_m, weak},
      {"gt3l", 1, true, pair_m - half_pair_m, 0.0, 1.0},
      {"gt3r", 2, false, pair_m + half_pair_m, weak_ahead_m, weak},
  }};
  return beams;
}

std::vector<AtlasBeam> select_atlas_beams(const std::vector<std::string>& names) {
  for (std::size_t i = 0; i < names.size(); ++i) {
    const auto known = std::find_if(atlas_beams().begin(), atlas_beams().end(),
                                    [&](const AtlasBeam& b) { return b.name == names[i]; });
    if (known == atlas_beams().end())
      throw std::invalid_argument("unknown beam \"" + names[i] +
                                  "\"; the beams are gt1l, gt1r, gt2l, gt2r, gt3l, gt3r");
    if (std::find(names.begin(), names.begin() + static_cast<std::ptrdiff_t>(i), names[i]) !=
        names.begin() + static_cast<std::ptrdiff_t>(i))
      throw std::invalid_argument("beam \"" + names[i] + "\" named twice");
  }
  std::vector<AtlasBeam> chosen;
  for (const AtlasBeam& beam : atlas_beams())
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
