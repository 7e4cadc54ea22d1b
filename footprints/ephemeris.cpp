// Reading ephemeris CSV files; every error names the file and line.
#include "footprints/ephemeris.hpp"

#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <string>
#include <string_view>

#include "footprints/glas_time.hpp"
#include "core/error.hpp"

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

std::string_view trimmed(std::string_view text) {
  const auto first = text.find_first_not_of(" \t\r");
  if (first == std::string_view::npos) return {};
  const auto last = text.find_last_not_of(" \t\r");
  return text.substr(first, last - first + 1);
}

std::vector<std::string_view> fields(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t start = 0;
  while (true) {
    const auto comma = line.find(',', start);
    out.push_back(trimmed(line.substr(
        start, comma == std::string_view::npos ? std::string_view::npos : comma - start)));
    if (comma == std::string_view::npos) return out;
    start = comma + 1;
  }
}

// The whole field as a finite number; from_chars, unlike strtod, never looks at the locale.
std::optional<double> number(std::string_view text) {
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);
  double value = 0.0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size() || !std::isfinite(value))
    return std::nullopt;
  return value;
}

}  // namespace

std::vector<EphemerisRow> read_ephemeris(const std::filesystem::path& file) {
  const std::string path = file.string();
  std::ifstream in(file);
  if (!in) throw input_error(path, "cannot open the ephemeris file");

  std::array<int, column_count> index;
  index.fill(-1);
  std::size_t field_count = 0;
  bool header_read = false, has_pointing = false;
  std::vector<EphemerisRow> rows;
  std::string line;
  for (long line_number = 1; std::getline(in, line); ++line_number) {
    const std::string_view text = trimmed(line);
    if (text.empty() || text.front() == '#') continue;
    const std::string place = path + ":" + std::to_string(line_number);
    const std::vector<std::string_view> parts = fields(text);

    if (!header_read) {
      for (std::size_t i = 0; i < parts.size(); ++i) {
        int column = -1;
        for (int c = 0; c < column_count; ++c)
          if (parts[i] == column_names[c]) column = c;
        if (column < 0) {
          throw input_error(place, "unknown column \"" + std::string(parts[i]) +
                                       "\"; the header row is " + header_help);
        }
        if (index[column] >= 0)
          throw input_error(place, "column \"" + std::string(parts[i]) + "\" appears twice");
        index[column] = static_cast<int>(i);
      }
      for (int c = time_column; c <= z_column; ++c) {
        if (index[c] < 0) {
          throw input_error(place, "missing column \"" + std::string(column_names[c]) +
                                       "\"; the header row is " + header_help);
        }
      }
      const int pointing_columns =
          (index[px_column] >= 0) + (index[py_column] >= 0) + (index[pz_column] >= 0);
      if (pointing_columns != 0 && pointing_columns != 3)
        throw input_error(
            place,
            "the pointing vector needs all three columns pointing_x, pointing_y, pointing_z");
      has_pointing = pointing_columns == 3;
      field_count = parts.size();
      header_read = true;
      continue;
    }

    if (parts.size() != field_count) {
      throw input_error(place, "expected " + std::to_string(field_count) +
                                   " fields as in the header, got " + std::to_string(parts.size()));
    }
    auto value = [&](Column column) {
      const std::string_view field = parts[index[column]];
      const auto parsed = number(field);
      if (!parsed) {
        throw input_error(place, std::string(column_names[column]) +
                                     ": expected a finite number, got \"" + std::string(field) +
                                     "\"");
      }
      return *parsed;
    };

    EphemerisRow row;
    const std::string_view time_text = parts[index[time_column]];
    if (const auto seconds = number(time_text)) {
      row.time_s = *seconds;
    } else {
      try {
        row.time_s = parse_iso8601_utc(std::string(time_text));
      } catch (const std::invalid_argument& e) {
        throw input_error(
            place, std::string("time: expected seconds since 2000-01-01T12:00:00Z or ISO 8601; ") +
                       e.what());
      }
    }
    row.spacecraft_ecef = {value(x_column), value(y_column), value(z_column)};
    const double height_m = geodetic_from_ecef(row.spacecraft_ecef).h_m;
    if (height_m <= 0.0) {
      char depth[32];
      std::snprintf(depth, sizeof depth, "%.1f", -height_m / 1000.0);
      throw input_error(place,
                        std::string("the spacecraft position is ") + depth +
                            " km under the WGS84 ellipsoid; positions are Earth-fixed metres");
    }
    if (has_pointing) {
      const Vec3 pointing{value(px_column), value(py_column), value(pz_column)};
      const double length = norm(pointing);
      if (!(length > 0.0) || !std::isfinite(length))
        throw input_error(place, "the pointing vector is zero");
      row.pointing_ecef = (1.0 / length) * pointing;
    }
    rows.push_back(row);
  }
  if (in.bad()) throw input_error(path, "cannot read the ephemeris file");
  if (!header_read)
    throw input_error(path,
                      std::string("empty ephemeris file; expected the header row ") + header_help);
  if (rows.empty())
    throw input_error(path, "the ephemeris file holds no shot (no row after the header)");
  return rows;
}

}  // namespace glaswave
