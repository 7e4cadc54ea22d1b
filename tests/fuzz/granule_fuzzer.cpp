// Fuzzes the granule reader (footprints/granule): GEDI L2A and GLAH14 HDF5 files, whole, cut
// and malformed. An input Error is a refusal; anything else (a crash, a hang, an allocation
// beyond libFuzzer's limit from a declared size) is a finding.
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
  return 0;
}
