// Time stamps of the GLAS products: seconds since the GLAS epoch, 2000-01-01T12:00:00Z, counted
// without leap seconds (every day has 86400 s), to and from ISO 8601 UTC text. In core because
// the tracks read times and the product writers write them.
#pragma once

#include <cstdint>
#include <string>

namespace glaswave {

// The GLAS epoch 2000-01-01T12:00:00Z in seconds since 1970-01-01T00:00:00Z (POSIX time, and CF's
// standard calendar, count no leap seconds): 10957 days and 12 hours.
inline constexpr std::int64_t glas_epoch_unix_s = 946728000;

// Parses "YYYY-MM-DDTHH:MM:SS[.fff...](Z|+00:00)" into seconds since 2000-01-01T12:00:00Z,
// ignoring leap seconds. Only UTC is accepted, so a time stamp never depends on a local zone.
// Throws std::invalid_argument on any other text, an impossible date or time, or a time outside
// [earliest_time_s, latest_time_s).
double parse_iso8601_utc(const std::string& text);

// The times a track may have, in seconds since the GLAS epoch: from 1900-01-01T00:00:00Z to
// 2200-01-01T00:00:00Z, wider than any spaceborne lidar's life and well inside what the
// products' ISO 8601 attributes write (years 0 to 9999). A time outside is a mistake of units
// (milliseconds for seconds), a fill value or a rate of next to nothing, not a time.
inline constexpr double earliest_time_s = -3155716800.0;  // 1900-01-01T00:00:00Z
inline constexpr double latest_time_s = 6311390400.0;     // 2200-01-01T00:00:00Z

// Empty when `seconds` is finite and within [earliest_time_s, latest_time_s); else the reason,
// for a message: "must be a finite time, got nan", "must be from 1900-01-01T00:00:00Z to
// 2200-01-01T00:00:00Z, got 1e+300 s from 2000-01-01T12:00:00Z".
std::string time_out_of_range(double seconds_since_glas_epoch);

// Writes seconds since 2000-01-01T12:00:00Z as "YYYY-MM-DDTHH:MM:SS[.ffffff]Z", with the
// fraction (to the microsecond, trailing zeros dropped) only when there is one.
// Throws std::invalid_argument for a non-finite value or a year outside 0..9999.
std::string format_iso8601_utc(double seconds_since_glas_epoch);

// Writes "YYYY-MM-DDTHH:MM:SS.ffffffZ", always six digits of fraction, as the NetCDF products'
// ACDD time attributes are written: the time is taken to POSIX seconds (a double) first, then
// rounded to the microsecond. Throws std::invalid_argument as format_iso8601_utc does.
std::string format_iso8601_utc_microseconds(double seconds_since_glas_epoch);

// When a product says it was made, as format_iso8601_utc_microseconds writes it: the
// SOURCE_DATE_EPOCH environment variable's time where it is set (reproducible-builds.org's
// convention: whole seconds since 1970-01-01T00:00:00Z, digits only), so that two identical runs
// write identical files; else the clock's. `reproducible` says which. Throws
// std::invalid_argument saying what the variable must be when it is set to anything else.
struct CreationTime {
  std::string iso8601;
  bool reproducible = false;
};
CreationTime product_creation_time();

}  // namespace glaswave
