// A small NetCDF-C handle for the retrieval's files (the forward table, retrieval.nc) and for
// reading glaswave's shots.nc: every call holds the library lock (core/netcdf_lock.hpp), every
// failure becomes one Error naming the file. Written files go to FINAL.part and are renamed when
// complete (core/atomic_file.hpp), so no half-written file lies under its final name.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/atomic_file.hpp"

namespace glaswave {

class NetcdfFile {
 public:
  // Opens `path` for reading; a missing or unreadable file, or one that is not NetCDF, is an
  // input error (exit status 3) naming it.
  static NetcdfFile open(const std::filesystem::path& path);
  // Creates FINAL.part (NetCDF-4); commit() closes it and renames it to `path`.
  static NetcdfFile create(const std::filesystem::path& path);

  NetcdfFile(NetcdfFile&&) noexcept;
  NetcdfFile& operator=(NetcdfFile&&) noexcept;
  ~NetcdfFile();

  const std::filesystem::path& path() const { return path_; }

  // ---- reading ----
  bool has_variable(const std::string& name) const;
  // The variable's dimension lengths; an input error when it is absent.
  std::vector<std::size_t> shape(const std::string& name) const;
  // The whole variable as doubles (its fill and NaN both read as NaN).
  std::vector<double> doubles(const std::string& name) const;
  std::vector<std::int64_t> integers(const std::string& name) const;
  // Part of a variable: `count` values along each dimension from `start`.
  std::vector<double> doubles(const std::string& name, const std::vector<std::size_t>& start,
                              const std::vector<std::size_t>& count) const;
  std::optional<std::string> text_attribute(const std::string& variable,
                                            const std::string& name) const;  // "" for global
  std::optional<double> number_attribute(const std::string& variable,
                                         const std::string& name) const;
  std::vector<std::string> strings(const std::string& name) const;  // an NC_STRING variable

  // ---- writing (define mode until end_define) ----
  void define_dimension(const std::string& name, std::size_t length);
  // A variable of NC_DOUBLE, NC_FLOAT, NC_INT, NC_INT64, NC_UBYTE or NC_STRING (nc_type), with
  // CF's units and long_name (units omitted when empty); floating ones get _FillValue NaN.
  void define_variable(const std::string& name, int type, const std::vector<std::string>& dims,
                       const std::string& units, const std::string& long_name);
  void put_text(const std::string& variable, const std::string& name, const std::string& value);
  void put_number(const std::string& variable, const std::string& name, double value);
  void put_bytes(const std::string& variable, const std::string& name,
                 const std::vector<std::uint8_t>& values);  // flag_values, flag_masks
  void end_define();
  void write(const std::string& name, const std::vector<double>& values);
  void write(const std::string& name, const std::vector<std::int64_t>& values);
  void write(const std::string& name, const std::vector<std::uint8_t>& values);
  void write(const std::string& name, const std::vector<std::string>& values);
  // Closes and renames FINAL.part to FINAL.
  void commit();

 private:
  NetcdfFile() = default;
  [[noreturn]] void fail(const std::string& message) const;
  void check(int status, const std::string& what) const;
  int variable_id(const std::string& name) const;
  int dimension_id(const std::string& name) const;

  std::filesystem::path path_;
  std::unique_ptr<AtomicFile> part_;  // set when writing
  int id_ = -1;
};

}  // namespace glaswave
