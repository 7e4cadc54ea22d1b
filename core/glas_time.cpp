// ISO 8601 UTC text <-> seconds since the GLAS epoch (2000-01-01T12:00:00Z), leap seconds
// ignored, with the proleptic Gregorian calendar arithmetic of H. Hinnant's days_from_civil.
#include "core/glas_time.hpp"

#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

#include "core/excerpt.hpp"

namespace glaswave {

namespace {

// Days from 1970-01-01 to the given date (proleptic Gregorian).
constexpr std::int64_t days_from_civil(std::int64_t y, int m, int d) {
  y -= m <= 2;
  const std::int64_t era = (y >= 0 ? y : y - 399) / 400;
  const std::int64_t yoe = y - era * 400;
  const std::int64_t doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const std::int64_t doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + doe - 719468;
}

// The inverse of days_from_civil.
void civil_from_days(std::int64_t z, std::int64_t& y, int& m, int& d) {
  z += 719468;
  const std::int64_t era = (z >= 0 ? z : z - 146096) / 146097;
  const std::int64_t doe = z - era * 146097;
  const std::int64_t yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
  const std::int64_t doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
  const std::int64_t mp = (5 * doy + 2) / 153;
  d = static_cast<int>(doy - (153 * mp + 2) / 5 + 1);
  m = static_cast<int>(mp < 10 ? mp + 3 : mp - 9);
  y = yoe + era * 400 + (m <= 2);
}

bool is_leap(std::int64_t y) { return (y % 4 == 0 && y % 100 != 0) || y % 400 == 0; }

int days_in_month(std::int64_t y, int m) {
  static const int days[] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  return m == 2 && is_leap(y) ? 29 : days[m - 1];
}

static_assert(days_from_civil(2000, 1, 1) * 86400 + 12 * 3600 == glas_epoch_unix_s);

// "YYYY-MM-DDTHH:MM:SSZ" with the fraction `micro` (0..999999) in six digits or, with `trim`,
// without its trailing zeros (and none at all when it is 0).
std::string write_utc(std::int64_t unix_s, std::int64_t micro, bool trim) {
  const std::int64_t days = unix_s >= 0 ? unix_s / 86400 : -((-unix_s + 86399) / 86400);
  const std::int64_t second_of_day = unix_s - days * 86400;
  std::int64_t year = 0;
  int month = 0, day = 0;
  civil_from_days(days, year, month, day);
  if (year < 0 || year > 9999) throw std::invalid_argument("time out of range for ISO 8601");

  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%04d-%02d-%02dT%02d:%02d:%02d", static_cast<int>(year),
                month, day, static_cast<int>(second_of_day / 3600),
                static_cast<int>(second_of_day / 60 % 60), static_cast<int>(second_of_day % 60));
  std::string out = buffer;
  if (!trim || micro != 0) {
    std::snprintf(buffer, sizeof buffer, ".%06d", static_cast<int>(micro));
    std::string fraction = buffer;
    while (trim && fraction.back() == '0') fraction.pop_back();
    out += fraction;
  }
  return out + "Z";
}

[[noreturn]] void bad(const std::string& text, const std::string& why) {
  throw std::invalid_argument(
      "not an ISO 8601 UTC time (YYYY-MM-DDTHH:MM:SSZ): " + quoted_excerpt(text) + ": " + why);
}

}  // namespace

double parse_iso8601_utc(const std::string& text) {
  std::size_t pos = 0;
  auto digits = [&](std::size_t count, const char* what) {
    int value = 0;
    for (std::size_t i = 0; i < count; ++i, ++pos) {
      if (pos >= text.size() || text[pos] < '0' || text[pos] > '9')
        bad(text, std::string("expected ") + std::to_string(count) + " digits of the " + what);
      value = value * 10 + (text[pos] - '0');
    }
    return value;
  };
  auto expect = [&](char c) {
    if (pos >= text.size() || text[pos] != c) bad(text, std::string("expected '") + c + "'");
    ++pos;
  };

  const int year = digits(4, "year");
  expect('-');
  const int month = digits(2, "month");
  expect('-');
  const int day = digits(2, "day");
  expect('T');
  const int hour = digits(2, "hour");
  expect(':');
  const int minute = digits(2, "minute");
  expect(':');
  const int second = digits(2, "second");
  double fraction = 0.0;
  if (pos < text.size() && text[pos] == '.') {
    ++pos;
    const std::size_t first = pos;
    while (pos < text.size() && text[pos] >= '0' && text[pos] <= '9') ++pos;
    if (pos == first) bad(text, "expected digits after '.'");
    // from_chars rounds correctly and, unlike strtod, never looks at the locale.
    const std::string digits_text = "0." + text.substr(first, pos - first);
    std::from_chars(digits_text.data(), digits_text.data() + digits_text.size(), fraction);
  }
  const std::string zone = text.substr(pos);
  // Only UTC: a time without a zone, or in another zone, would be a guess about the user's intent.
  if (zone != "Z" && zone != "+00:00") bad(text, "expected the zone 'Z' or '+00:00'");

  if (month < 1 || month > 12) bad(text, "month out of range");
  if (day < 1 || day > days_in_month(year, month)) bad(text, "day out of range");
  if (hour > 23) bad(text, "hour out of range");
  if (minute > 59) bad(text, "minute out of range");
  // Leap seconds are not counted, so 23:59:60 has no place on this time scale.
  if (second > 59) bad(text, "second out of range");

  const std::int64_t unix_s =
      days_from_civil(year, month, day) * 86400 + hour * 3600 + minute * 60 + second;
  const double seconds = static_cast<double>(unix_s - glas_epoch_unix_s) + fraction;
  if (!(seconds >= earliest_time_s && seconds < latest_time_s))
    throw std::invalid_argument(quoted_excerpt(text) +
                                " is outside the years 1900 to 2199 that a track may have");
  return seconds;
}

std::string time_out_of_range(double seconds) {
  if (seconds >= earliest_time_s && seconds < latest_time_s) return "";
  char text[64];
  std::snprintf(text, sizeof text, "%.6g", seconds);
  if (!std::isfinite(seconds)) return "must be a finite time, got " + std::string(text);
  return "must be from 1900-01-01T00:00:00Z to 2200-01-01T00:00:00Z, got " + std::string(text) +
         " s from 2000-01-01T12:00:00Z";
}

std::string format_iso8601_utc(double seconds_since_glas_epoch) {
  if (!std::isfinite(seconds_since_glas_epoch))
    throw std::invalid_argument("cannot write a non-finite time as ISO 8601");
  // Work in whole microseconds so that rounding never produces ":60" or ".1000000".
  const double micro_total = std::round(seconds_since_glas_epoch * 1e6);
  if (std::fabs(micro_total) > 4.0e17)  // about ±12700 years: outside 0..9999 anyway
    throw std::invalid_argument("time out of range for ISO 8601");
  const std::int64_t micro = static_cast<std::int64_t>(micro_total) + glas_epoch_unix_s * 1000000;
  const std::int64_t seconds = micro >= 0 ? micro / 1000000 : -((-micro + 999999) / 1000000);
  return write_utc(seconds, micro - seconds * 1000000, true);
}

std::string format_iso8601_utc_microseconds(double seconds_since_glas_epoch) {
  if (!std::isfinite(seconds_since_glas_epoch) || std::fabs(seconds_since_glas_epoch) > 4.0e11)
    throw std::invalid_argument("time out of range for ISO 8601");
  // The POSIX time as a double, then its fraction rounded: the products' attributes have always
  // been written so, and must stay the same bits.
  const double unix_s = static_cast<double>(glas_epoch_unix_s) + seconds_since_glas_epoch;
  double whole_s = std::floor(unix_s);
  auto micro = static_cast<std::int64_t>(std::llround((unix_s - whole_s) * 1e6));
  if (micro >= 1000000) {
    whole_s += 1.0;
    micro -= 1000000;
  }
  return write_utc(static_cast<std::int64_t>(whole_s), micro, false);
}

CreationTime product_creation_time() {
  const char* epoch = std::getenv("SOURCE_DATE_EPOCH");
  if (epoch) {
    const std::string text(epoch);
    std::int64_t unix_s = -1;
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), unix_s);
    const double glas_s = static_cast<double>(unix_s - glas_epoch_unix_s);
    if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos ||
        error != std::errc() || end != text.data() + text.size() ||
        !time_out_of_range(glas_s).empty())
      throw std::invalid_argument(
          "must be whole seconds since "
          "1970-01-01T00:00:00Z, digits only (as `date +%s` writes), "
          "got '" +
          excerpt(text) + "'");
    return {format_iso8601_utc_microseconds(glas_s), true};
  }
  const auto now = std::chrono::system_clock::now();
  const auto micro =
      std::chrono::duration_cast<std::chrono::microseconds>(now.time_since_epoch()).count();
  return {format_iso8601_utc_microseconds(static_cast<double>(micro / 1000000 - glas_epoch_unix_s) +
                                          static_cast<double>(micro % 1000000) * 1e-6),
          false};
}

}  // namespace glaswave
