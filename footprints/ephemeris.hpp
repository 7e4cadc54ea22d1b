// Ephemeris tracks: a CSV file of shot times and Earth-fixed spacecraft positions, with an
// optional pointing vector per shot.
//
// The file has a header row naming its columns, in any order:
//   time,x_m,y_m,z_m[,pointing_x,pointing_y,pointing_z]
// `time` is ISO 8601 UTC ("2005-10-21T12:00:00.025Z") or seconds since 2000-01-01T12:00:00Z;
// x_m, y_m, z_m is the spacecraft position in WGS84 ECEF (m); pointing_x/y/z, all three or none,
// is the beam direction in ECEF (any length; spacecraft -> ground). Without it each shot points
// as a pass does: geodetic nadir tilted by track.off_nadir_deg toward track.pointing_azimuth_deg.
// One shot a row, numbered from 0 in file order. Blank lines and lines starting with '#' are
// skipped; fields may be padded with spaces.
#pragma once

#include <filesystem>
#include <optional>
#include <vector>

#include "terrain/local_frame.hpp"

namespace glaswave {

struct EphemerisRow {
  double time_s = 0.0;  // seconds since the GLAS epoch
  Vec3 spacecraft_ecef{};
  std::optional<Vec3> pointing_ecef;  // unit vector, when the file gives one
};

// Reads the whole file. Throws an input Error (exit status 3) whose place is "PATH:LINE" for
// a bad row or header (bad number, missing or unknown column, bad time, a position under the
// ground), and "PATH" for a file that cannot be read or holds no row.
std::vector<EphemerisRow> read_ephemeris(const std::filesystem::path& file);

}  // namespace glaswave
