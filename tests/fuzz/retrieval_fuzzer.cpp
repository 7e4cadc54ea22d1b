// Fuzzes `glaswave retrieve`'s granule readers (pipeline/retrieval): GEDI L1B and L2A, GLAS
// GLAH01 and GLAH14 and ICESat-2 ATL08 HDF5 files, whole, cut and malformed, each read in this
// process through the one HDF5 layer as retrieve reads it. An input Error is a refusal; anything
// else (a crash, a hang, memory beyond what the file can hold) is a finding. Each reader is
// called on the input whatever its kind, so that a GLAH01 is read without first needing a
// GLAH14 beside it: the GLAH14 it is placed by is fixed here, its first shots matching the
// seeds'. glaswave's shots.nc (NetCDF) is not fuzzed here. library_leaks.supp suppresses leaks
// with a frame inside HDF5; a file or object left open traps instead.
#include <hdf5.h>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include "core/error.hpp"
#include "pipeline/retrieval/atl08_reader.hpp"
#include "pipeline/retrieval/gedi_l1b_reader.hpp"
#include "pipeline/retrieval/glas_granule_reader.hpp"
#include "pipeline/retrieval/retrieve_inputs.hpp"
#include "tests/fuzz/fuzz_support.hpp"

namespace {

glaswave::Glah14Shots placed() {
  glaswave::Glah14Shots shots;
  for (std::int64_t number : {40000, 40001, 40079})
    shots.shots.emplace_back(
        number, glaswave::Glah14Shot{1.0, 2.0, 101.0, -1.0, 100.0, 0.5, 1.0, 10.0, 0.5});
  return shots;
}

template <typename Read>
void attempt(Read read) {
  try {
    read();
  } catch (const glaswave::Error& e) {
    glaswave::fuzz::refused(e);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const glaswave::Glah14Shots glah14 = placed();
  const auto file = glaswave::fuzz::write_input("granule.h5", data, size);
  attempt([&] { glaswave::retrieve_input_kind(file); });
  attempt([&] { glaswave::read_gedi_l1b(file, glaswave::read_gedi_l2a(file), {}, {}); });
  attempt([&] { glaswave::read_gedi_l1b(file, {}, {}, {}); });
  attempt([&] { glaswave::read_glah01(file, glaswave::read_glah14(file), {}, {}); });
  attempt([&] { glaswave::read_glah01(file, glah14, {}, {}); });
  attempt([&] { glaswave::read_atl08(file, {}, {}); });
  // No HDF5 file or object left open, on refusal too: what library_leaks.supp's HDF5 line would
  // otherwise hide.
  if (H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_ALL) != 0) __builtin_trap();
  return 0;
}
