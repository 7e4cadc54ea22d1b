// The header of a classic NetCDF file (CDF-1, CDF-2 and CDF-5, big-endian) checked against the
// file's size before libnetcdf reads it: nc_open allocates what the header declares before it
// reads it (a 23-byte file declaring 1.1e9 dimensions asked for 9 GB), as Assimp does a PLY's
// counts. Each count of dimensions, attributes, variables and a variable's dimensions, and each
// name's and attribute's length, must fit in the bytes left after it.
#pragma once

#include <filesystem>
#include <string>

namespace glaswave {

// An input error naming `place` for a header that declares more than the file holds, or is cut.
// A file that does not start with "CDF" is not looked at.
void check_classic_netcdf_header(const std::filesystem::path& file, const std::string& place);

}  // namespace glaswave
