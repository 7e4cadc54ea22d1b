// A mission granule open for `glaswave retrieve` to read (GEDI L1B and L2A, GLAS GLAH01 and
// GLAH14): every dataset checked (present, numeric, its shape, a size the file can hold) before it
// is read, every refusal one line naming the file and the dataset. Reads go through the one HDF5
// layer (core/hdf5_file.hpp); the caller holds libnetcdf's lock (core/netcdf_lock.hpp).
#pragma once

#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "core/hdf5_file.hpp"

namespace glaswave {

class GranuleFile {
 public:
  // `kind` names what the file should be in refusals ("a GEDI L1B or L2A granule").
  GranuleFile(const std::filesystem::path& file, std::string kind);

  const Hdf5Reader& reader() const { return reader_; }
  const std::string& place() const { return place_; }

  [[noreturn]] void refuse(const std::string& dataset, const std::string& why) const;

  // A numeric dataset of `rank` dimensions whose first is `count` (any count when nullopt), all
  // of it in C order; `dims` receives its dimensions.
  template <typename T>
  std::vector<T> read(const std::string& dataset, std::optional<std::size_t> count,
                      std::size_t rank = 1, std::vector<std::uint64_t>* dims = nullptr) const;
  // As read(), NaN everywhere when the dataset is absent.
  std::vector<double> optional(const std::string& dataset, std::size_t count) const;
  // The first of `names` present (the names of one field in different product releases).
  std::vector<double> first_of(const std::string& group, std::initializer_list<const char*> names,
                               std::size_t count) const;

 private:
  Hdf5Reader reader_;
  std::string place_, kind_;
  std::uintmax_t bytes_;
};

}  // namespace glaswave
