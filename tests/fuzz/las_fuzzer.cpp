// Fuzzes the LAS reader (canopy/las_reader): bytes -> a file -> LasFile (header, variable length
// records, extended records), its CRS, and every point read back in windows. An input Error is a
// refusal; anything else (a crash, a read out of bounds, an allocation beyond the limit) is a
// finding.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "canopy/las_reader.hpp"
#include "core/error.hpp"
#include "tests/fuzz/fuzz_support.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  glaswave::fuzz::keep_only_gdal_drivers({});  // the CRS goes through OGR/PROJ, no raster driver
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace glaswave;
  const auto file = fuzz::write_input("input.las", data, size);
  try {
    const LasFile las(file);
    try {
      las_crs(las, "EPSG:32633", "/canopy/point_cloud/crs");
    } catch (const Error& e) {
      fuzz::refused(e);
    }
    std::vector<LasPoint> points;
    const std::uint64_t count = las.header().point_count;
    for (std::uint64_t first = 0; first < count; first += 1000) {
      points.clear();
      las.read_points(first, 1000, points);
    }
    las.read_points(count, 5, points);  // past the end: nothing
  } catch (const Error& e) {
    fuzz::refused(e);
  }
  return 0;
}
