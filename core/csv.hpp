// Reading the CSV files of glaswave (ephemeris, crowns): rows split at commas, fields trimmed of
// spaces, blank lines and lines starting with '#' skipped, numbers read without the locale, and
// every error naming the file and line.
#pragma once

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.hpp"

namespace glaswave {

// The whole text as a finite number, with std::from_chars: a decimal point whatever the locale,
// a leading '+' allowed, nothing else around the number. Empty when it is not one.
std::optional<double> parse_number(std::string_view text);

// The fields of one line, split at commas and trimmed of spaces, tabs and carriage returns.
std::vector<std::string_view> split_csv_line(std::string_view line);

// A field of a file for an error message: quoted when it is short and plain (letters, digits,
// "_.+-" and `also`), else only its length, so that a file of another kind (a system file) is
// never echoed.
std::string field_excerpt(std::string_view field, std::string_view also = "");

class CsvReader {
 public:
  // Lines and files beyond these are not CSV of glaswave's (a row is a few numbers): refused.
  static constexpr std::size_t max_line_bytes = 4096;
  static constexpr std::uintmax_t max_file_bytes = std::uintmax_t{1} << 30;

  // Opens the file, a regular file of at most max_file_bytes (a device such as /dev/zero would
  // be read for ever); `what` names it in errors ("the ephemeris file").
  CsvReader(const std::filesystem::path& file, std::string what);

  // The next row that holds something, as fields that stay valid until the next call; false at
  // the end of the file (an input error if the file could not be read to its end).
  bool next_row(std::vector<std::string_view>& fields);

  // "PATH:LINE" of the row last read, for errors about it; and the file's path.
  std::string place() const { return path_ + ":" + std::to_string(line_number_); }
  const std::string& path() const { return path_; }

  // The field `name` of the row last read as a finite number, else an input error at the row.
  double number(std::string_view field, std::string_view name) const;

 private:
  std::string path_;
  std::string what_;
  std::ifstream in_;
  std::string line_;
  bool read_line();
  long line_number_ = 0;
};

}  // namespace glaswave
