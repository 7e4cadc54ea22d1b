// GLAS granules as `glaswave retrieve`'s input: GLAH01 (the received waveforms, their noise and
// sample times) read beside its GLAH14 (where each waveform lies: the centroid's elevation and its
// range offset), real or glaswave's glah01.h5 and glah14.h5 (docs/granules.md), matched shot by
// shot. A malformed granule is refused with one line naming the file and the dataset.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <utility>
#include <vector>

#include "pipeline/retrieval/retrieve.hpp"

namespace glaswave {

// A GLAS shot's number: its 1 s record and its shot in the record (1 to 40), i_rec_ndx x 40 +
// i_shot_count - 1 (glaswave's own granules: the run's shot number).
std::int64_t glas_shot_number(std::int64_t rec_ndx, std::int64_t shot_count);

// One GLAH14 shot as the GLAH01 reader places its waveform. NaN where the granule has fill.
struct Glah14Shot {
  double lat_deg, lon_deg;
  double elev_m;         // d_elev: the waveform's centroid
  double land_offset_m;  // d_ldRngOff: the centroid's range less d_refRng (the last gate's)
  double dem_m;          // d_DEM_elv
  // glaswave's truth (glaswave_truth), NaN in a real granule.
  double cover, pai, canopy_height_m, pgap;
};

struct Glah14Shots {
  bool simulated = false;                                  // glaswave's granule: its truth is read
  std::vector<std::pair<std::int64_t, Glah14Shot>> shots;  // by shot number, sorted
};

// Every shot of a GLAH14 granule.
Glah14Shots read_glah14(const std::filesystem::path& file);

// The shots of a GLAH01 granule with numbers in [first, last) when given, each placed by its
// GLAH14 shot: r_rng_wf in the granule's units (counts_per_W from glaswave_truth/counts_per_watt
// in glaswave's granules, else unknown), its noise d_4nsBgMean and d_4nsBgSDEV, its samples'
// times from ANCILLARY_DATA's rec_wf_sample_location_table (evenly spaced, as GLAS's 544-sample
// land waveforms are; a compressed row is refused). The last sample lies at d_elev + d_ldRngOff,
// each sample before it half a light-nanosecond higher: the beam is taken as vertical (within a
// degree of nadir, as GLAS pointed, a sample 100 m from the centroid moves by at most 1.5 cm). A
// shot GLAH14 lacks, whose elevation is fill or whose sample-location row is fill (127) is kept
// and not good.
MeasuredShots read_glah01(const std::filesystem::path& file, const Glah14Shots& glah14,
                          std::optional<std::int64_t> first, std::optional<std::int64_t> last);

}  // namespace glaswave
