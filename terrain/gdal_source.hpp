// The regular-file rule (core/input_file.hpp) for what GDAL opens: a plain path must be a regular
// file; a /vsi path, one GDAL reads from a file (an archive's /vsizip/, /vsigzip/, /vsitar/ ...)
// whose local file is regular, or GDAL's memory (/vsimem/); a streaming one (/vsistdin/,
// /vsicurl_streaming/ ...) is refused, as it would be waited on. A VRT's source files (and its
// sources' sources) are held to the same rule before GDAL opens any of them.
#pragma once

#include <string>

#include "core/error.hpp"

namespace glaswave {

// Throws Error(kind) at the path (or at the VRT's source that breaks the rule) unless GDAL may
// open it without waiting; `what` names it in the message ("the DEM").
void require_gdal_source(const std::string& path, const std::string& what,
                         ErrorKind kind = ErrorKind::input);

}  // namespace glaswave
