// CSV rows and locale-independent numbers, with errors at file:line.
#include "core/csv.hpp"

#include <charconv>
#include <cmath>

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

CsvReader::CsvReader(const std::filesystem::path& file, std::string what)
    : path_(file.string()), what_(std::move(what)), in_(file) {
  if (!in_) throw input_error(path_, "cannot open " + what_);
}

bool CsvReader::next_row(std::vector<std::string_view>& fields) {
  while (std::getline(in_, line_)) {
    ++line_number_;
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
  throw input_error(place(), std::string(name) + ": expected a finite number, got \"" +
                                 std::string(field) + "\"");
}

}  // namespace glaswave
