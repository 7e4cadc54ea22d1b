// ICESat-2 ATL03 granules as `glaswave retrieve`'s input, read beside their ATL08: each land
// segment's photons (ATL03's 20 m geolocation segments segment_id_beg to segment_id_end), which
// rt compares with its table's expected photons under Poisson's law (rt_inversion.hpp). Real
// ATL03 or glaswave's atl03.h5 (docs/icesat2.md); a malformed granule is refused with one line
// naming the file and the dataset.
#pragma once

#include <filesystem>

#include "pipeline/retrieval/retrieve.hpp"

namespace glaswave {

// ATLAS fires 10,000 pulses a second (the ATL03 ATBD, section 2).
inline constexpr double kAtlasPulseRate_Hz = 10000.0;

// Whether `file` (an HDF5 file) holds a gtXY/heights/h_ph dataset.
bool is_atl03(const std::filesystem::path& file);

// Gives each ATL08 land segment of `segments` (read_atl08's) whose beam the granule holds its
// photons (PhotonSegment): heights/h_ph of its geolocation segments (segment_id, ph_index_beg
// 1-based, segment_ph_cnt), each placed along track at segment_dist_x + dist_ph_along and
// brought to the middle of their span on ATL08's terrain_slope; the pulses from the segments'
// delta_time at ATLAS's rate; bckgrd_atlas/bckgrd_rate averaged over the segment's time; and
// glaswave_truth/photons_per_joule when the granule is glaswave's. Every beam present is read
// whole, segments or not (the reader program reads it with none).
void attach_atl03(const std::filesystem::path& file, MeasuredShots& segments);

}  // namespace glaswave
