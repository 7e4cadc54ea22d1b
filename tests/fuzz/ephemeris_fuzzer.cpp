// Fuzzes the ephemeris reader (footprints/ephemeris): a CSV of times, ECEF positions and
// pointing. An input Error is a refusal; anything else is a finding.
#include <cstddef>
#include <cstdint>

#include "core/error.hpp"
#include "footprints/ephemeris.hpp"
#include "tests/fuzz/fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = glaswave::fuzz::write_input("ephemeris.csv", data, size);
  try {
    glaswave::read_ephemeris(file);
  } catch (const glaswave::Error& e) {
    glaswave::fuzz::refused(e);
  }
  return 0;
}
