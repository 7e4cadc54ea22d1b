// The one rule for the files glaswave reads (configuration, DEM, crowns, stands, ephemeris,
// granule, run journal): a path without a NUL byte that names a regular file with data. Anything
// else is refused by its path before it is opened: a FIFO nobody writes would be waited on for
// ever, a device (/dev/zero) read for ever, a pseudo-file of /proc or /sys (/proc/self/mem)
// cannot be read as a file of data, and a NUL would cut the path where the C library reads it.
#pragma once

#include <string>
#include <string_view>

#include "core/error.hpp"

namespace glaswave {

// `path` printable in a message: a NUL byte and other control characters shown as \0, \n, \xHH.
std::string printable_path(std::string_view path);

// Throws Error(kind) naming `place` if `path` holds a NUL byte.
void require_no_nul(std::string_view path, const std::string& place, ErrorKind kind);

// Throws Error(kind) at the path unless it names a regular file outside /proc and /sys (links
// followed); `what` names the file in the message ("the DEM"). Nothing is opened.
void require_input_file(std::string_view path, const std::string& what,
                        ErrorKind kind = ErrorKind::input);

}  // namespace glaswave
