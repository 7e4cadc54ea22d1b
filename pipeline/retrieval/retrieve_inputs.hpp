// `glaswave retrieve`'s inputs (PRODUCT.md section 11): each file's kind read from its layout, not
// its name, and every input read by its kind into the measured shots the methods take.
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
  glah01,    // Data_40HZ/Waveform/RecWaveform/r_rng_wf
  glah14,    // Data_40HZ/Elevation_Surfaces/d_elev and no r_rng_wf
  atl08,     // gtXY/land_segments
  atl03,     // gtXY/heights/h_ph
};

// The kind of `file` from what it holds.
RetrieveInputKind retrieve_input_kind(const std::filesystem::path& file);

// Every input read first by the program glaswave-read-retrieval-input, in a process of its own
// with a CPU budget (core/spawned_reader.hpp), so that a file on which HDF5 1.10.8 or libnetcdf
// crashes, spins or allocates without end (fuzzing found a 10 kB GLAH01 on which HDF5 took 24 GB)
// is refused, then read here by its kind: shots.nc files, GEDI L1B granules (each with the L2A
// granules given, whose shots it matches), GLAH01 granules (placed by the GLAH14 granules given)
// and ATL08 granules (a record a land segment, with the photons of the one ATL03 granule given
// beside one ATL08), their shots in the order given. An L2A without an L1B, a GLAH14 without a
// GLAH01, a GLAH01 without a GLAH14 or an ATL03 without one ATL08 is refused, as are inputs whose
// bands or bins differ.
MeasuredShots read_retrieve_inputs(const std::vector<std::filesystem::path>& inputs,
                                   std::optional<std::int64_t> first,
                                   std::optional<std::int64_t> last);

// The reader program's main: reads argv[1] whole by its kind and replies whether it could.
int retrieval_input_reader_main(int argc, char** argv);

}  // namespace glaswave
