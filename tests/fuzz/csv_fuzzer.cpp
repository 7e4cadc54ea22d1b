// Fuzzes the CSV reading of core/csv (rows, fields, numbers) and the crowns file reader on top
// of it (canopy/forest), with and without a plane terrain. An input Error is a refusal; anything
// else is a finding.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

#include "canopy/forest.hpp"
#include "core/csv.hpp"
#include "tests/fuzz/fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace glaswave;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  parse_number(text);
  split_csv_line(text);
  const auto file = fuzz::write_input("input.csv", data, size);
  try {
    CsvReader csv(file, "the fuzzed file");
    std::vector<std::string_view> fields;
    while (csv.next_row(fields)) {
      for (const std::string_view field : fields) {
        try {
          csv.number(field, "field");
        } catch (const Error& e) {
          fuzz::refused(e);
        }
      }
    }
  } catch (const Error& e) {
    fuzz::refused(e);
  }
  for (const std::optional<PlaneSettings>& plane :
       {std::optional<PlaneSettings>{}, std::optional<PlaneSettings>{PlaneSettings{}}}) {
    try {
      read_crowns_file(file, plane);
    } catch (const Error& e) {
      fuzz::refused(e);
    }
  }
  return 0;
}
