// `glaswave retrieve`'s inputs (PRODUCT.md section 11): each file's kind read from its layout,
// not its name, and GEDI L1B granules (GEDI01_B's layout, real or glaswave's gedi_l1b.h5) read
// into the measured shots the methods take, with the L2A granule given beside them (its ground,
// selected group, quality flag and sensitivity, matched by shot number). Every dataset goes
// through the one HDF5 layer (core/hdf5_file.hpp); a malformed granule is refused with one line
// naming the file and the dataset, its declared sizes checked before anything is allocated.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <vector>

#include "pipeline/retrieval/retrieve.hpp"

namespace glaswave {

enum class RetrieveInputKind {
  shots_nc,  // glaswave's shots.nc (or anything else: read_shots says what it is not)
  gedi_l1b,  // BEAMxxxx groups holding rxwaveform
  gedi_l2a,  // BEAMxxxx groups holding elev_lowestmode and no rxwaveform
};

// The kind of `file` from what it holds.
RetrieveInputKind retrieve_input_kind(const std::filesystem::path& file);

// One L2A shot as the L2B algorithm takes it from an L2A granule.
struct GediL2aShot {
  int selected_algorithm = 0;  // 1..6; 0 when the granule has no selected_algorithm
  double elev_lowestmode_m, elev_highestreturn_m, sensitivity;
  std::uint8_t quality_flag = 0;
};

// Every shot of an L2A granule (real GEDI02_A or glaswave's gedi_l2a.h5), by shot number.
std::vector<std::pair<std::uint64_t, GediL2aShot>> read_gedi_l2a(const std::filesystem::path& file);

// The shots of a GEDI L1B granule with shot numbers in [first, last) when given, beam by beam;
// those found in `l2a` (sorted by shot number) carry its fields. Waveforms in the granule's
// counts, noise from noise_mean_corrected and noise_stddev_corrected; bins of 1 ns (GEDI's
// digitiser), placed by geolocation/elevation_bin0 and elevation_lastbin; the beam's zenith from
// geolocation/local_beam_elevation, else from the line from bin 0 to the last bin. glaswave's own
// granules carry their truth (glaswave_truth).
MeasuredShots read_gedi_l1b(const std::filesystem::path& file,
                            const std::vector<std::pair<std::uint64_t, GediL2aShot>>& l2a,
                            std::optional<std::int64_t> first, std::optional<std::int64_t> last);

// Every input read by its kind: shots.nc files and L1B granules (each with the L2A granules
// given, whose shots it matches), their shots in the order given. An L2A granule without an L1B
// is refused, as are inputs whose bands or bins differ.
MeasuredShots read_retrieve_inputs(const std::vector<std::filesystem::path>& inputs,
                                   std::optional<std::int64_t> first,
                                   std::optional<std::int64_t> last);

// The L2A group the L2B algorithm runs on: the L2A granule's selected group and its ground and
// highest return where one was given, else glaswave's own selection (`result`). `selected`
// receives the group's number (1..6, 0 for none).
L2aGroupResult gedi_l2a_choice(const L2aResult& result, const GediShotInfo& info, int& selected);

}  // namespace glaswave
