// The shots of a track: where the spacecraft is, where the laser points, and where the beam
// axis meets the terrain (the footprint centre), as GLAS geolocation did.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "footprints/track_settings.hpp"
#include "terrain/local_frame.hpp"
#include "terrain/terrain.hpp"

namespace glaswave {

struct Footprint {
  std::int64_t shot_number = 0;
  double time_s = 0.0;  // seconds since 2000-01-01T12:00:00Z
  Geodetic spacecraft;
  Vec3 spacecraft_ecef{};
  Vec3 beam_ecef{};  // unit vector of the beam axis, spacecraft -> ground
  double off_nadir_deg = 0.0;
  bool on_terrain = false;  // false: the beam axis never met the terrain (flagged shot)
  Geodetic ground;          // footprint centre, when on_terrain
  double range_m = 0.0;     // spacecraft to footprint centre
};

// Unit vector (ECEF) of a beam tilted `off_nadir_deg` from the geodetic nadir at the
// spacecraft, toward the azimuth `pointing_azimuth_deg` (clockwise from north).
Vec3 pointing_direction(const Geodetic& spacecraft, double off_nadir_deg, double pointing_azimuth_deg);

// Where a ray first meets the terrain: against the WGS84 ellipsoid in closed form, then refined
// against the terrain's heights until it moves less than 1 mm. Empty when it never meets it.
std::optional<Vec3> intersect_terrain(const Terrain& terrain, const Vec3& origin_ecef,
                                      const Vec3& direction_ecef);

// The footprints of shots [first, last) of the track (last clamped to the track's length).
std::vector<Footprint> plan_track(const TrackSettings& track, const Terrain& terrain,
                                  std::int64_t first, std::int64_t last);

// Number of shots in the track.
std::int64_t track_length(const TrackSettings& track);

}  // namespace glaswave
