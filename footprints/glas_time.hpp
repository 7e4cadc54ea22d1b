// Time stamps of the GLAS products: seconds since the GLAS epoch, 2000-01-01T12:00:00Z, counted
// without leap seconds (every day has 86400 s), to and from ISO 8601 UTC text.
#pragma once

#include <string>

namespace glaswave {

// Parses "YYYY-MM-DDTHH:MM:SS[.fff...](Z|+00:00)" into seconds since 2000-01-01T12:00:00Z,
// ignoring leap seconds. Only UTC is accepted, so a time stamp never depends on a local zone.
// Throws std::invalid_argument on any other text or an impossible date or time.
double parse_iso8601_utc(const std::string& text);

// Writes seconds since 2000-01-01T12:00:00Z as "YYYY-MM-DDTHH:MM:SS[.ffffff]Z", with the
// fraction (to the microsecond, trailing zeros dropped) only when there is one.
// Throws std::invalid_argument for a non-finite value or a year outside 0..9999.
std::string format_iso8601_utc(double seconds_since_glas_epoch);

}  // namespace glaswave
