// Fuzzes the stands file: GeoJSON bytes -> the file a configuration names as canopy.stands ->
// read_stand_features (GDAL/OGR) and the checks of each feature's canopy keys in
// load_config_document. All of GDAL's drivers stay (the reader calls GDALAllRegister on every
// read, which under GDAL_SKIP registers and drops some 200 drivers each time: 7 inputs a second
// instead of 23). An Error is a refusal; anything else is a finding.
#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "pipeline/config/config.hpp"
#include "tests/fuzz/fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace glaswave;
  const auto file = fuzz::write_input("stands.geojson", data, size);
  const nlohmann::json document = {
      {"terrain", {{"plane", nlohmann::json::object()}}},
      {"canopy", {{"pai", 3}, {"crown_shape", "ellipsoid"}, {"stands", "stands.geojson"}}}};
  try {
    load_config_document(document, file.parent_path(), {});
  } catch (const Error& e) {
    fuzz::refused(e);
  }
  return 0;
}
