// Granule tracks: the shots of a real GEDI L2A or GLAS GLAH14 granule (HDF5).
//
// GEDI L2A: every group `BEAMxxxx` at the root with the datasets `shot_number` (an unsigned or
// signed integer), `lat_lowestmode`, `lon_lowestmode` (deg) and `delta_time` (s since
// 2018-01-01T00:00:00Z); `degrade_flag` where there is one. The beam's number is its name's four
// digits read in binary (BEAM0101 is 5, as the granule's `beam` dataset says).
// GLAH14: the group `Data_40HZ` with `Geolocation/d_lat`, `Geolocation/d_lon` (deg),
// `Time/d_UTCTime_40` (s since 2000-01-01T12:00:00Z), `Time/i_rec_ndx` (the 1 s record of each
// 40 Hz shot) and `Time/i_shot_count` (the shot within its record, 1 to 40); a shot's number is
// i_rec_ndx * 40 + i_shot_count - 1, true also where a record lacks its first shots.
//
// Integers stay integers: a shot number, record index or shot count stored as floating point is
// refused, as is a shot number beyond 2^63 - 1 or below 0, or an i_shot_count outside 1..40.
// Sizes are checked before anything is read: a dataset of more than kMostGranuleShots values is
// refused. A footprint whose latitude or longitude is a fill value (not finite, or outside
// [-90, 90] and [-180, 360]) is no shot of the track, and the reader says how many it skipped.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace glaswave {

// The most shots one beam of a granule may hold: a whole GEDI granule's beam holds about
// 3.5e5, a GLAH14 granule (one day of 40 Hz shots) about 3.5e6.
inline constexpr std::int64_t kMostGranuleShots = 5'000'000;

// GEDI's beam types (the beam groups' `description` attribute): the coverage beams are the two
// halves of one laser, the full-power beams each a whole laser's pulse (BEAM0000..BEAM0011 are
// coverage, BEAM0101, BEAM0110, BEAM1000, BEAM1011 full power).
inline bool gedi_coverage_beam(int beam) { return beam >= 0 && beam < 4; }

struct GranuleShot {
  std::int64_t shot_number = 0;  // the granule's own
  double time_s = 0.0;           // seconds since the GLAS epoch, 2000-01-01T12:00:00Z
  double lat_deg = 0.0, lon_deg = 0.0;
  int beam = -1;                   // GEDI: the beam's number; -1 for GLAH14
  std::uint8_t degrade_flag = 0;   // GEDI's degrade_flag, 0 where the granule has none
  std::int64_t record_index = -1;  // GLAH14 i_rec_ndx; -1 for GEDI
  int shot_count = 0;              // GLAH14 i_shot_count (1..40); 0 for GEDI
};

// The shots of the granule, beam by beam in the order asked (GEDI: `beams`, or every BEAM group
// in name order when empty; GLAH14 has one beam, `Data_40HZ`, and `beams` must be empty or name
// it), in file order within a beam. Throws an input Error (exit status 3) naming the file, and
// the group where one is at fault, for a missing or unreadable file, a file of neither layout, a
// beam not in the file or named twice, a dataset too large, an integer of the wrong kind or out
// of range, or a granule without a shot. `warnings`, when given, receives one line when
// footprints with a fill position were skipped.
//
// HDF5 1.10 (Debian 12's) crashes on some corrupt files, in ways no check of the bytes before it
// covers, and a library must not fork: the granule is read by the small program
// glaswave-read-granule, started with posix_spawn (which runs no fork handlers, so a thread
// holding PROJ's or another library's lock cannot hang it). A crash there refuses the file. The
// program is looked for, first found: beside the binary holding this code, in bin/ beside it
// (the pip package's glaswave/bin/ for its module), in ../libexec/glaswave/ from it (an installed
// prefix), where the build made it, and in the install prefix's libexec/glaswave/.
std::vector<GranuleShot> read_granule(const std::filesystem::path& file,
                                      const std::vector<std::string>& beams,
                                      std::vector<std::string>* warnings = nullptr);

// glaswave-read-granule's whole work: `argv` is the program, the granule, then the beams. Writes
// the shots, or the error, and the warnings to standard output for read_granule; 0 when all of it
// was written.
int granule_reader_main(int argc, char** argv);

}  // namespace glaswave
