// ICESat-2 ATL08 granules as `glaswave retrieve`'s input: each beam's land segments (100 m along
// track), real or glaswave's atl08.h5 (docs/icesat2.md), read into one measured record a segment
// that carries ATL08's canopy height, best-fit terrain and photon counts by class in place of a
// waveform. A malformed granule is refused with one line naming the file and the dataset.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>

#include "pipeline/retrieval/retrieve.hpp"

namespace glaswave {

// ICESat-2's ground tracks, in the order retrieval.nc numbers them (beam 1 to 6).
inline constexpr std::array<const char*, 6> kAtlasTracks = {"gt1l", "gt1r", "gt2l",
                                                            "gt2r", "gt3l", "gt3r"};

// Whether `file` (an HDF5 file) holds a gtXY/land_segments group.
bool is_atl08(const std::filesystem::path& file);

// The land segments of every beam (gt1l, gt1r, ..., gt3r: beam 1 to 6 in retrieval.nc) whose
// segment_id_beg (the record's shot number) is in [first, last) when given: latitude,
// longitude, canopy/h_canopy, terrain/h_te_best_fit, canopy/n_ca_photons and n_toc_photons,
// terrain/n_te_photons, segment_id_end and terrain/terrain_slope (when present); ATL08's fill
// (3.4028235e38) read as missing. glaswave's own granules carry their truth
// (land_segments/glaswave_truth).
MeasuredShots read_atl08(const std::filesystem::path& file, std::optional<std::int64_t> first,
                         std::optional<std::int64_t> last);

}  // namespace glaswave
