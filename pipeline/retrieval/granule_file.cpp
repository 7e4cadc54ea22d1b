#include "pipeline/retrieval/granule_file.hpp"

#include "core/error.hpp"

namespace glaswave {
namespace {

// deflate compresses at most 1032 to 1: a dataset declaring more values than that ratio allows
// for the file's bytes is not stored in it, and is refused before anything is allocated.
constexpr double kMostDeflateRatio = 1032.0;

std::uintmax_t file_bytes(const std::filesystem::path& file) {
  std::error_code error;
  const std::uintmax_t bytes = std::filesystem::file_size(file, error);
  return error ? 0 : bytes;
}

}  // namespace

GranuleFile::GranuleFile(const std::filesystem::path& file, std::string kind)
    : reader_(file), place_(file.string()), kind_(std::move(kind)), bytes_(file_bytes(file)) {}

void GranuleFile::refuse(const std::string& dataset, const std::string& why) const {
  throw input_error(place_, dataset + ": " + why);
}

template <typename T>
std::vector<T> GranuleFile::read(const std::string& dataset, std::optional<std::size_t> count,
                                 std::size_t rank, std::vector<std::uint64_t>* dims) const {
  const std::optional<Hdf5DatasetShape> shape = reader_.shape(dataset);
  if (!shape) refuse(dataset, "missing (" + kind_ + " has it)");
  if (!shape->numeric) refuse(dataset, "not numeric");
  if (shape->dims.size() != rank)
    refuse(dataset, rank == 1 ? std::string("not one-dimensional")
                              : "not " + std::to_string(rank) + "-dimensional");
  if (count && shape->dims[0] != *count)
    refuse(dataset, "holds " + std::to_string(shape->dims[0]) + (rank == 1 ? " values" : " rows") +
                        " for " + std::to_string(*count) + " shots");
  double values_declared = 1.0;
  for (std::uint64_t d : shape->dims) values_declared *= static_cast<double>(d);
  if (values_declared > kMostDeflateRatio * static_cast<double>(bytes_) + 1e6)
    refuse(dataset, "declares " + std::to_string(static_cast<std::uint64_t>(values_declared)) +
                        " values, more than a file of " + std::to_string(bytes_) +
                        " bytes can hold");
  std::vector<T> values;
  if (!reader_.read(dataset, values)) refuse(dataset, "cannot be read (a truncated file?)");
  if (dims) *dims = shape->dims;
  return values;
}

template std::vector<double> GranuleFile::read(const std::string&, std::optional<std::size_t>,
                                               std::size_t, std::vector<std::uint64_t>*) const;
template std::vector<std::int64_t> GranuleFile::read(const std::string&, std::optional<std::size_t>,
                                                     std::size_t,
                                                     std::vector<std::uint64_t>*) const;
template std::vector<std::uint64_t> GranuleFile::read(const std::string&,
                                                      std::optional<std::size_t>, std::size_t,
                                                      std::vector<std::uint64_t>*) const;

std::vector<double> GranuleFile::optional(const std::string& dataset, std::size_t count) const {
  if (!reader_.has(dataset))
    return std::vector<double>(count, std::numeric_limits<double>::quiet_NaN());
  return read<double>(dataset, count);
}

std::vector<double> GranuleFile::first_of(const std::string& group,
                                          std::initializer_list<const char*> names,
                                          std::size_t count) const {
  for (const char* name : names)
    if (reader_.has(group + "/" + name)) return read<double>(group + "/" + name, count);
  return std::vector<double>(count, std::numeric_limits<double>::quiet_NaN());
}

}  // namespace glaswave
