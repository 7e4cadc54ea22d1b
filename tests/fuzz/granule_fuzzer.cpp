// Fuzzes the granule reader (footprints/granule): GEDI L2A and GLAH14 HDF5 files, whole, cut
// and malformed. An input Error is a refusal; anything else (a crash, a hang, an allocation
// beyond libFuzzer's limit from a declared size, an HDF5 object left open) is a finding.
#include <hdf5.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "footprints/granule.hpp"
#include "tests/fuzz/fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = glaswave::fuzz::write_input("granule.h5", data, size);
  try {
    std::vector<std::string> warnings;
    glaswave::read_granule(file, {}, &warnings);
  } catch (const glaswave::Error& e) {
    glaswave::fuzz::refused(e);
  }
  // Every handle the reader opened is closed, on refusal too (HDF5's own leaks are suppressed).
  if (H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_ALL) != 0) __builtin_trap();
  return 0;
}
