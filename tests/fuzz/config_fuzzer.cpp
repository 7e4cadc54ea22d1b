// Fuzzes the configuration: JSON text -> typed Config, through what `check` and `run` call
// (read_json_file, load_config_document, check_outputs; the engine's memory estimate reads no
// input of its own beyond the ephemeris, which has its own target). A glaswave::Error is a refusal,
// the right end for a bad input; anything else (a crash, another exception, undefined behaviour, a
// leak) is a finding. A stands file named by the input is kept inside the scratch folder (the
// stands reader has its own target) so that no input reads files elsewhere.
#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

#include "core/error.hpp"
#include "pipeline/config/config.hpp"
#include "tests/fuzz/fuzz_support.hpp"

namespace {

// A stands path other than a plain file name (which stays in the scratch folder) becomes one.
void keep_stands_inside(nlohmann::json& document) {
  if (!document.is_object() || !document.contains("canopy")) return;
  nlohmann::json& canopy = document["canopy"];
  if (!canopy.is_object() || !canopy.contains("stands") || !canopy["stands"].is_string()) return;
  const std::string name = canopy["stands"];
  if (name.find('/') != std::string::npos || name.find("..") != std::string::npos ||
      name.find('\\') != std::string::npos)
    canopy["stands"] = "stands.geojson";
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  // A stands file for inputs that name one (all of GDAL's drivers stay: see stands_fuzzer.cpp).
  const std::string stands = R"({"type": "FeatureCollection", "features": [{"type": "Feature",
      "properties": {"pai": 1}, "geometry": {"type": "Polygon", "coordinates":
      [[[7, 45], [7.001, 45], [7.001, 45.001], [7, 45]]]}}]})";
  glaswave::fuzz::write_input("stands.geojson",
                              reinterpret_cast<const std::uint8_t*>(stands.data()), stands.size());
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace glaswave;
  const auto file = fuzz::write_input("config.json", data, size);
  try {
    nlohmann::json document = read_json_file(file);
    keep_stands_inside(document);
    const Config config = load_config_document(std::move(document), file.parent_path(), {});
    check_outputs(config);
  } catch (const Error& e) {
    fuzz::refused(e);
  }
  return 0;
}
