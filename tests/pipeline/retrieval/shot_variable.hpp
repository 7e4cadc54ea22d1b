// retrieval.nc read back in the retrieval tests: one per-shot variable, empty when the file or
// the variable is not there.
#pragma once

#include <netcdf.h>

#include <filesystem>
#include <vector>

namespace glaswave::test_support {

inline std::vector<double> shot_variable(const std::filesystem::path& file, const char* name) {
  int nc = -1, var = -1, dim = -1;
  std::size_t length = 0;
  std::vector<double> values;
  if (nc_open(file.c_str(), NC_NOWRITE, &nc) != NC_NOERR) return values;
  if (nc_inq_varid(nc, name, &var) == NC_NOERR && nc_inq_dimid(nc, "shot", &dim) == NC_NOERR &&
      nc_inq_dimlen(nc, dim, &length) == NC_NOERR) {
    values.resize(length);
    nc_get_var_double(nc, var, values.data());
  }
  nc_close(nc);
  return values;
}

}  // namespace glaswave::test_support
