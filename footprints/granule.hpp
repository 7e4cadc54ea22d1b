// Granule tracks: the shots of a real GEDI L2A or GLAS GLAH14 granule (HDF5).
//
// GEDI L2A: every group `BEAMxxxx` at the root with the datasets `shot_number` (uint64),
// `lat_lowestmode`, `lon_lowestmode` (deg) and `delta_time` (s since 2018-01-01T00:00:00Z).
// GLAH14: the group `Data_40HZ` with `Geolocation/d_lat`, `Geolocation/d_lon` (deg),
// `Time/d_UTCTime_40` (s since 2000-01-01T12:00:00Z) and `Time/i_rec_ndx` (the 1 s record of
// each 40 Hz shot); a shot's number is i_rec_ndx * 40 + its place among its record's shots.
// A footprint whose latitude or longitude is a fill value (not finite, or outside [-90, 90] and
// [-180, 360]) is skipped: it is no shot of the track.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace glaswave {

struct GranuleShot {
  std::int64_t shot_number = 0;  // the granule's own
  double time_s = 0.0;           // seconds since the GLAS epoch, 2000-01-01T12:00:00Z
  double lat_deg = 0.0, lon_deg = 0.0;
};

// The shots of the granule, beam by beam in the order asked (GEDI: `beams`, or every BEAM group
// in name order when empty; GLAH14 has one beam, `Data_40HZ`, and `beams` must be empty or name
// it), in file order within a beam. Throws an input Error (exit status 3) naming the file, and
// the group where one is at fault, for a missing or unreadable file, a file of neither layout, a
// beam not in the file, or a granule without a shot.
std::vector<GranuleShot> read_granule(const std::filesystem::path& file,
                                      const std::vector<std::string>& beams);

}  // namespace glaswave
