// GEDI L1B granules as `glaswave retrieve`'s input (PRODUCT.md section 11): GEDI01_B's layout,
// real or glaswave's gedi_l1b.h5, read into the measured shots the methods take, with the L2A
// granule given beside them (its ground, selected group, quality flag and sensitivity, matched by
// shot number). Every dataset goes through GranuleFile: a malformed granule is refused with one
// line naming the file and the dataset, its declared sizes checked before anything is allocated.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <vector>

#include "pipeline/retrieval/retrieve.hpp"

namespace glaswave {

// One L2A shot as the L2B algorithm takes it from an L2A granule.
struct GediL2aShot {
  int selected_algorithm = 0;  // 1..6; 0 when the granule has no selected_algorithm
  double elev_lowestmode_m, elev_highestreturn_m, sensitivity;
  std::uint8_t quality_flag = 0;
};

// Every shot of an L2A granule (real GEDI02_A or glaswave's gedi_l2a.h5), by shot number.
std::vector<std::pair<std::uint64_t, GediL2aShot>> read_gedi_l2a(const std::filesystem::path& file);

// Whether `file` (an HDF5 file) holds BEAMxxxx groups with rxwaveform (L1B), or with
// elev_lowestmode and no rxwaveform (L2A).
bool is_gedi_l1b(const std::filesystem::path& file);
bool is_gedi_l2a(const std::filesystem::path& file);

// The shots of a GEDI L1B granule with shot numbers in [first, last) when given, beam by beam;
// those found in `l2a` (sorted by shot number) carry its fields. Waveforms in the granule's
// counts, noise from noise_mean_corrected and noise_stddev_corrected; bins of 1 ns (GEDI's
// digitiser), placed by geolocation/elevation_bin0 and elevation_lastbin; the beam's zenith from
// geolocation/local_beam_elevation, else from the line from bin 0 to the last bin. glaswave's own
// granules carry their truth (glaswave_truth).
MeasuredShots read_gedi_l1b(const std::filesystem::path& file,
                            const std::vector<std::pair<std::uint64_t, GediL2aShot>>& l2a,
                            std::optional<std::int64_t> first, std::optional<std::int64_t> last);

// The L2A group the L2B algorithm runs on: the L2A granule's selected group and its ground and
// highest return where one was given, else glaswave's own selection (`result`). `selected`
// receives the group's number (1..6, 0 for none).
L2aGroupResult gedi_l2a_choice(const L2aResult& result, const GediShotInfo& info, int& selected);

}  // namespace glaswave
