// NetcdfFile: NetCDF-C under the library lock, its failures one Error naming the file.
#include "pipeline/retrieval/netcdf_file.hpp"

#include <netcdf.h>

#include <cerrno>
#include <cmath>
#include <limits>
#include <mutex>

#include "core/error.hpp"
#include "core/netcdf_lock.hpp"
#include "core/write_error.hpp"

namespace glaswave {

namespace {
using Lock = std::lock_guard<std::mutex>;
constexpr std::size_t kMaxValues = std::size_t{1} << 31;  // what one variable may hold (16 GiB)
}  // namespace

NetcdfFile NetcdfFile::open(const std::filesystem::path& path) {
  NetcdfFile file;
  file.path_ = path;
  if (!std::filesystem::is_regular_file(path)) file.fail("no such file");
  Lock lock(netcdf_library_mutex());
  if (nc_open(path.c_str(), NC_NOWRITE, &file.id_) != NC_NOERR) {
    file.id_ = -1;
    file.fail("not a NetCDF file, or unreadable");
  }
  return file;
}

NetcdfFile NetcdfFile::create(const std::filesystem::path& path) {
  NetcdfFile file;
  file.path_ = path;
  file.part_ = std::make_unique<AtomicFile>(path);
  Lock lock(netcdf_library_mutex());
  const int status = nc_create(file.part_->part_path().c_str(), NC_NETCDF4 | NC_CLOBBER, &file.id_);
  if (status != NC_NOERR) {
    file.id_ = -1;
    file.check(status, "creating it");
  }
  return file;
}

NetcdfFile::NetcdfFile(NetcdfFile&& other) noexcept
    : path_(std::move(other.path_)), part_(std::move(other.part_)), id_(other.id_) {
  other.id_ = -1;
}

NetcdfFile& NetcdfFile::operator=(NetcdfFile&& other) noexcept {
  std::swap(path_, other.path_);
  std::swap(part_, other.part_);
  std::swap(id_, other.id_);
  return *this;
}

NetcdfFile::~NetcdfFile() {
  if (id_ < 0) return;
  Lock lock(netcdf_library_mutex());
  if (part_)
    nc_abort(id_);  // the .part is then removed by AtomicFile
  else
    nc_close(id_);
}

void NetcdfFile::fail(const std::string& message) const {
  if (part_) throw run_error(path_.string(), message);
  throw input_error(path_.string(), message);
}

void NetcdfFile::check(int status, const std::string& what) const {
  if (status == NC_NOERR) return;
  const int error_number = errno;
  if (part_ && no_space(error_number)) fail(write_failure(error_number) + " (" + what + ")");
  fail(what + ": " + nc_strerror(status));
}

int NetcdfFile::variable_id(const std::string& name) const {
  int varid = -1;
  if (nc_inq_varid(id_, name.c_str(), &varid) != NC_NOERR) fail("no variable `" + name + "`");
  return varid;
}

int NetcdfFile::dimension_id(const std::string& name) const {
  int dimid = -1;
  if (nc_inq_dimid(id_, name.c_str(), &dimid) != NC_NOERR) fail("no dimension `" + name + "`");
  return dimid;
}

bool NetcdfFile::has_variable(const std::string& name) const {
  Lock lock(netcdf_library_mutex());
  int varid = -1;
  return nc_inq_varid(id_, name.c_str(), &varid) == NC_NOERR;
}

std::vector<std::size_t> NetcdfFile::shape(const std::string& name) const {
  Lock lock(netcdf_library_mutex());
  const int varid = variable_id(name);
  int ndims = 0;
  check(nc_inq_varndims(id_, varid, &ndims), "reading `" + name + "`");
  if (ndims > NC_MAX_VAR_DIMS) fail("`" + name + "` has too many dimensions");
  std::vector<int> dims(ndims);
  check(nc_inq_vardimid(id_, varid, dims.data()), "reading `" + name + "`");
  std::vector<std::size_t> lengths(ndims);
  std::size_t total = 1;
  for (int d = 0; d < ndims; ++d) {
    check(nc_inq_dimlen(id_, dims[d], &lengths[d]), "reading `" + name + "`");
    total = lengths[d] == 0
                ? 0
                : (total > kMaxValues / lengths[d] ? kMaxValues + 1 : total * lengths[d]);
  }
  if (total > kMaxValues) fail("`" + name + "` is too large to read");
  return lengths;
}

std::vector<double> NetcdfFile::doubles(const std::string& name) const {
  const std::vector<std::size_t> lengths = shape(name);
  return doubles(name, std::vector<std::size_t>(lengths.size(), 0), lengths);
}

std::vector<double> NetcdfFile::doubles(const std::string& name,
                                        const std::vector<std::size_t>& start,
                                        const std::vector<std::size_t>& count) const {
  std::size_t total = 1;
  for (std::size_t c : count) total *= c;
  std::vector<double> values(total);
  Lock lock(netcdf_library_mutex());
  const int varid = variable_id(name);
  nc_type type = NC_NAT;
  check(nc_inq_vartype(id_, varid, &type), "reading `" + name + "`");
  if (type == NC_CHAR || type == NC_STRING) fail("`" + name + "` is not numeric");
  if (total > 0)
    check(nc_get_vara_double(id_, varid, start.data(), count.data(), values.data()),
          "reading `" + name + "`");
  double fill = std::numeric_limits<double>::quiet_NaN();
  if (nc_get_att_double(id_, varid, "_FillValue", &fill) == NC_NOERR && !std::isnan(fill))
    for (double& v : values)
      if (v == fill) v = std::numeric_limits<double>::quiet_NaN();
  return values;
}

std::vector<std::int64_t> NetcdfFile::integers(const std::string& name) const {
  const std::vector<std::size_t> lengths = shape(name);
  std::size_t total = 1;
  for (std::size_t c : lengths) total *= c;
  std::vector<long long> values(total);
  Lock lock(netcdf_library_mutex());
  const int varid = variable_id(name);
  if (total > 0) check(nc_get_var_longlong(id_, varid, values.data()), "reading `" + name + "`");
  return {values.begin(), values.end()};
}

std::vector<std::string> NetcdfFile::strings(const std::string& name) const {
  const std::vector<std::size_t> lengths = shape(name);
  if (lengths.size() != 1) fail("`" + name + "` must have one dimension");
  Lock lock(netcdf_library_mutex());
  const int varid = variable_id(name);
  nc_type type = NC_NAT;
  check(nc_inq_vartype(id_, varid, &type), "reading `" + name + "`");
  if (type != NC_STRING) fail("`" + name + "` is not a string variable");
  std::vector<char*> texts(lengths[0], nullptr);
  if (!texts.empty()) check(nc_get_var_string(id_, varid, texts.data()), "reading `" + name + "`");
  std::vector<std::string> out;
  for (char* t : texts) out.emplace_back(t ? t : "");
  if (!texts.empty()) nc_free_string(texts.size(), texts.data());
  return out;
}

std::optional<std::string> NetcdfFile::text_attribute(const std::string& variable,
                                                      const std::string& name) const {
  Lock lock(netcdf_library_mutex());
  const int varid = variable.empty() ? NC_GLOBAL : variable_id(variable);
  nc_type type = NC_NAT;
  std::size_t length = 0;
  if (nc_inq_att(id_, varid, name.c_str(), &type, &length) != NC_NOERR) return std::nullopt;
  if (type == NC_CHAR) {
    if (length > kMaxValues) fail("attribute `" + name + "` is too large");
    std::string text(length, '\0');
    check(nc_get_att_text(id_, varid, name.c_str(), text.data()), "reading `" + name + "`");
    return text;
  }
  if (type == NC_STRING && length == 1) {
    char* text = nullptr;
    check(nc_get_att_string(id_, varid, name.c_str(), &text), "reading `" + name + "`");
    std::string out = text ? text : "";
    nc_free_string(1, &text);
    return out;
  }
  return std::nullopt;
}

std::optional<double> NetcdfFile::number_attribute(const std::string& variable,
                                                   const std::string& name) const {
  Lock lock(netcdf_library_mutex());
  const int varid = variable.empty() ? NC_GLOBAL : variable_id(variable);
  nc_type type = NC_NAT;
  std::size_t length = 0;
  if (nc_inq_att(id_, varid, name.c_str(), &type, &length) != NC_NOERR || length != 1 ||
      type == NC_CHAR || type == NC_STRING)
    return std::nullopt;
  double value = 0.0;
  check(nc_get_att_double(id_, varid, name.c_str(), &value), "reading `" + name + "`");
  return value;
}

void NetcdfFile::define_dimension(const std::string& name, std::size_t length) {
  Lock lock(netcdf_library_mutex());
  int dimid = -1;
  check(nc_def_dim(id_, name.c_str(), length, &dimid), "defining dimension `" + name + "`");
}

void NetcdfFile::define_variable(const std::string& name, int type,
                                 const std::vector<std::string>& dims, const std::string& units,
                                 const std::string& long_name) {
  std::vector<int> dimids;
  {
    Lock lock(netcdf_library_mutex());
    for (const std::string& d : dims) dimids.push_back(dimension_id(d));
    int varid = -1;
    const std::string what = "defining `" + name + "`";
    check(
        nc_def_var(id_, name.c_str(), type, static_cast<int>(dimids.size()), dimids.data(), &varid),
        what);
    if (dims.size() >= 2 && type != NC_STRING) check(nc_def_var_deflate(id_, varid, 1, 1, 4), what);
    if (type == NC_DOUBLE) {
      const double fill = std::numeric_limits<double>::quiet_NaN();
      check(nc_put_att_double(id_, varid, "_FillValue", NC_DOUBLE, 1, &fill), what);
    } else if (type == NC_FLOAT) {
      const float fill = std::numeric_limits<float>::quiet_NaN();
      check(nc_put_att_float(id_, varid, "_FillValue", NC_FLOAT, 1, &fill), what);
    }
  }
  if (!units.empty()) put_text(name, "units", units);
  put_text(name, "long_name", long_name);
}

void NetcdfFile::put_text(const std::string& variable, const std::string& name,
                          const std::string& value) {
  Lock lock(netcdf_library_mutex());
  const int varid = variable.empty() ? NC_GLOBAL : variable_id(variable);
  check(nc_put_att_text(id_, varid, name.c_str(), value.size(), value.c_str()),
        "writing attribute `" + name + "`");
}

void NetcdfFile::put_number(const std::string& variable, const std::string& name, double value) {
  Lock lock(netcdf_library_mutex());
  const int varid = variable.empty() ? NC_GLOBAL : variable_id(variable);
  check(nc_put_att_double(id_, varid, name.c_str(), NC_DOUBLE, 1, &value),
        "writing attribute `" + name + "`");
}

void NetcdfFile::put_bytes(const std::string& variable, const std::string& name,
                           const std::vector<std::uint8_t>& values) {
  Lock lock(netcdf_library_mutex());
  const int varid = variable_id(variable);
  check(nc_put_att_uchar(id_, varid, name.c_str(), NC_UBYTE, values.size(), values.data()),
        "writing attribute `" + name + "`");
}

void NetcdfFile::end_define() {
  Lock lock(netcdf_library_mutex());
  check(nc_enddef(id_), "defining the file");
}

void NetcdfFile::write(const std::string& name, const std::vector<double>& values) {
  if (values.empty()) return;
  Lock lock(netcdf_library_mutex());
  check(nc_put_var_double(id_, variable_id(name), values.data()), "writing `" + name + "`");
}

void NetcdfFile::write(const std::string& name, const std::vector<std::int64_t>& values) {
  if (values.empty()) return;
  const std::vector<long long> copy(values.begin(), values.end());
  Lock lock(netcdf_library_mutex());
  check(nc_put_var_longlong(id_, variable_id(name), copy.data()), "writing `" + name + "`");
}

void NetcdfFile::write(const std::string& name, const std::vector<std::uint8_t>& values) {
  if (values.empty()) return;
  Lock lock(netcdf_library_mutex());
  check(nc_put_var_uchar(id_, variable_id(name), values.data()), "writing `" + name + "`");
}

void NetcdfFile::write(const std::string& name, const std::vector<std::string>& values) {
  if (values.empty()) return;
  std::vector<const char*> texts;
  for (const std::string& v : values) texts.push_back(v.c_str());
  Lock lock(netcdf_library_mutex());
  check(nc_put_var_string(id_, variable_id(name), texts.data()), "writing `" + name + "`");
}

void NetcdfFile::commit() {
  {
    Lock lock(netcdf_library_mutex());
    const int status = nc_close(id_);
    id_ = -1;
    check(status, "closing it");
  }
  part_->commit();
}

}  // namespace glaswave
