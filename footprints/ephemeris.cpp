// Reading ephemeris CSV files; every error names the file and line.
#include "footprints/ephemeris.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <string_view>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/glas_time.hpp"

namespace glaswave {
namespace {

enum Column {
  time_column,
  x_column,
  y_column,
  z_column,
  px_column,
  py_column,
  pz_column,
  column_count
};
constexpr std::array<std::string_view, column_count> column_names = {
    "time", "x_m", "y_m", "z_m", "pointing_x", "pointing_y", "pointing_z"};
constexpr const char* header_help = "time,x_m,y_m,z_m[,pointing_x,pointing_y,pointing_z]";

// Where each column is in a row, from the header row.
struct Columns {
  std::array<int, column_count> index;
  std::size_t count = 0;
  bool has_pointing = false;
};

Columns read_header(const std::vector<std::string_view>& parts, const std::string& place) {
  Columns columns;
  columns.index.fill(-1);
  for (std::size_t i = 0; i < parts.size(); ++i) {
    int column = -1;
    for (int c = 0; c < column_count; ++c)
      if (parts[i] == column_names[c]) column = c;
    if (column < 0) {
      throw input_error(place, "column " + std::to_string(i + 1) + " is not a column name (" +
                                   field_excerpt(parts[i]) + "); the header row is " + header_help);
    }
    if (columns.index[column] >= 0)
      throw input_error(place, "column " + field_excerpt(parts[i]) + " appears twice");
    columns.index[column] = static_cast<int>(i);
  }
  for (int c = time_column; c <= z_column; ++c) {
    if (columns.index[c] < 0) {
      throw input_error(place, "missing column \"" + std::string(column_names[c]) +
                                   "\"; the header row is " + header_help);
    }
  }
  const int pointing_columns = (columns.index[px_column] >= 0) + (columns.index[py_column] >= 0) +
                               (columns.index[pz_column] >= 0);
  if (pointing_columns != 0 && pointing_columns != 3)
    throw input_error(
        place, "the pointing vector needs all three columns pointing_x, pointing_y, pointing_z");
  columns.has_pointing = pointing_columns == 3;
  columns.count = parts.size();
  return columns;
}

double read_time(std::string_view text, const std::string& place) {
  if (const auto seconds = parse_number(text)) {
    if (const std::string why = time_out_of_range(*seconds); !why.empty())
      throw input_error(place, "time " + why);
    return *seconds;
  }
  try {
    return parse_iso8601_utc(std::string(text));
  } catch (const std::invalid_argument& e) {
    if (std::string_view(e.what()).find("outside the years") != std::string_view::npos)
      throw input_error(place, "time outside the years 1900 to 2199 that a track may have");
    // The field is named, not echoed whole: the file may be of another kind.
    throw input_error(place,
                      "time: expected seconds since 2000-01-01T12:00:00Z or ISO 8601 UTC "
                      "(YYYY-MM-DDTHH:MM:SSZ), got " +
                          field_excerpt(text, ":"));
  }
}

EphemerisRow read_row(const CsvReader& csv, const std::vector<std::string_view>& parts,
                      const Columns& columns) {
  const std::string place = csv.place();
  if (parts.size() != columns.count) {
    throw input_error(place, "expected " + std::to_string(columns.count) +
                                 " fields as in the header, got " + std::to_string(parts.size()));
  }
  auto value = [&](Column column) {
    return csv.number(parts[columns.index[column]], column_names[column]);
  };
  EphemerisRow row;
  row.time_s = read_time(parts[columns.index[time_column]], place);
  row.spacecraft_ecef = {value(x_column), value(y_column), value(z_column)};
  const double height_m = geodetic_from_ecef(row.spacecraft_ecef).h_m;
  if (height_m <= 0.0) {
    char depth[32];
    std::snprintf(depth, sizeof depth, "%.1f", -height_m / 1000.0);
    throw input_error(place, std::string("the spacecraft position is ") + depth +
                                 " km under the WGS84 ellipsoid; positions are Earth-fixed metres");
  }
  if (columns.has_pointing) {
    const Vec3 pointing{value(px_column), value(py_column), value(pz_column)};
    // Any length: scaled by its largest component first, so that a vector of 1e300 (whose
    // squares overflow) points as one of 1 does.
    const double largest =
        std::max({std::abs(pointing[0]), std::abs(pointing[1]), std::abs(pointing[2])});
    if (!std::isfinite(largest)) throw input_error(place, "the pointing vector is not finite");
    if (!(largest > 0.0)) throw input_error(place, "the pointing vector is zero");
    const Vec3 scaled = (1.0 / largest) * pointing;
    row.pointing_ecef = (1.0 / norm(scaled)) * scaled;
  }
  return row;
}

}  // namespace

std::vector<EphemerisRow> read_ephemeris(const std::filesystem::path& file) {
  CsvReader csv(file, "the ephemeris file");
  std::vector<std::string_view> parts;
  if (!csv.next_row(parts))
    throw input_error(csv.path(),
                      std::string("empty ephemeris file; expected the header row ") + header_help);
  const Columns columns = read_header(parts, csv.place());
  std::vector<EphemerisRow> rows;
  while (csv.next_row(parts)) rows.push_back(read_row(csv, parts, columns));
  if (rows.empty())
    throw input_error(csv.path(), "the ephemeris file holds no shot (no row after the header)");
  return rows;
}

}  // namespace glaswave
