// Fuzzes the granule reader (footprints/granule): GEDI L2A and GLAH14 HDF5 files, whole, cut
// and malformed, through read_granule as the library calls it: the file is read by the program
// glaswave-read-granule (footprints/granule.hpp), whose reply read_granule decodes. An input Error
// is a refusal; anything else in this process (a crash, a hang, a reply taken for shots it does
// not hold) is a finding. What crashes the reader program (HDF5 1.10 on some corrupt files) is a
// refusal by design: its sanitizer's report, if any, is in the log. libFuzzer's coverage does not
// reach into that program, so this target searches the reply's decoding and the file rule.
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
