// CSV rows and locale-independent numbers, with errors at file:line.
#include "core/csv.hpp"

#include <cctype>
#include <charconv>
#include <cmath>

#include "core/excerpt.hpp"
#include "core/input_file.hpp"

namespace glaswave {
namespace {

std::string_view trimmed(std::string_view text) {
  const auto first = text.find_first_not_of(" \t\r");
  if (first == std::string_view::npos) return {};
  const auto last = text.find_last_not_of(" \t\r");
  return text.substr(first, last - first + 1);
}

}  // namespace

std::optional<double> parse_number(std::string_view text) {
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);
  double value = 0.0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || error != std::errc() || end != text.data() + text.size() ||
      !std::isfinite(value))
    return std::nullopt;
  return value;
}

std::vector<std::string_view> split_csv_line(std::string_view line) {
  std::vector<std::string_view> fields;
  std::size_t start = 0;
  while (true) {
    const auto comma = line.find(',', start);
    fields.push_back(trimmed(line.substr(
        start, comma == std::string_view::npos ? std::string_view::npos : comma - start)));
    if (comma == std::string_view::npos) return fields;
    start = comma + 1;
  }
}

std::string field_excerpt(std::string_view field, std::string_view also) {
  constexpr std::size_t max_length = 32;
  bool plain = field.size() <= max_length;
  for (char c : field)
    plain = plain && (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.' ||
                      c == '+' || c == '-' || also.find(c) != std::string_view::npos);
  if (plain) return quoted_excerpt(field);
  return "a field of " + std::to_string(field.size()) + " characters";
}

CsvReader::CsvReader(const std::filesystem::path& file, std::string what)
    : path_(file.string()), what_(std::move(what)) {
  require_input_file(path_, what_);  // a FIFO or a device is waited on or read for ever
  std::error_code error;
  if (std::filesystem::file_size(file, error) > max_file_bytes)
    throw input_error(path_, what_ + " is larger than the limit of " +
                                 std::to_string(max_file_bytes >> 20) + " MiB");
  in_.open(file, std::ios::binary);
  if (!in_) throw input_error(path_, "cannot open " + what_);
}

// The next line into line_, without its newline; false at the end of the file. A line longer
// than max_line_bytes is refused before it is held.
bool CsvReader::read_line() {
  line_.clear();
  std::streambuf* buffer = in_.rdbuf();
  for (int c = buffer->sbumpc(); c != std::char_traits<char>::eof(); c = buffer->sbumpc()) {
    if (c == '\n') return true;
    if (line_.size() == max_line_bytes)
      throw input_error(path_ + ":" + std::to_string(line_number_ + 1),
                        "a line longer than " + std::to_string(max_line_bytes) + " bytes: not " +
                            what_ + " (CSV text)");
    line_.push_back(static_cast<char>(c));
  }
  return !line_.empty();
}

bool CsvReader::next_row(std::vector<std::string_view>& fields) {
  while (read_line()) {
    ++line_number_;
    // A UTF-8 byte order mark (a spreadsheet's "CSV UTF-8") is no part of the header.
    constexpr std::string_view bom = "\xEF\xBB\xBF";
    if (line_number_ == 1 && std::string_view(line_).substr(0, bom.size()) == bom)
      line_.erase(0, bom.size());
    const std::string_view text = trimmed(line_);
    if (text.empty() || text.front() == '#') continue;
    fields = split_csv_line(text);
    return true;
  }
  if (in_.bad()) throw input_error(path_, "cannot read " + what_);
  return false;
}

double CsvReader::number(std::string_view field, std::string_view name) const {
  if (const auto value = parse_number(field)) return *value;
  throw input_error(place(),
                    std::string(name) + ": expected a finite number, got " + field_excerpt(field));
}

}  // namespace glaswave
