// The one HDF5 layer: a writer of whole datasets and their attributes, addressed by path, and a
// reader of one-dimensional numeric datasets, over the HDF5 C library. Every object is written
// without HDF5's object time stamps, so that the same data give the same bytes. HDF5 (Debian's,
// not built thread-safe) lies under libnetcdf too: callers hold netcdf_library_mutex() around a
// writer's or reader's whole life (core/netcdf_lock.hpp).
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace glaswave {

// A dataset's or group's text attributes, in the order written (units, long_name, ...).
struct Hdf5Attribute {
  std::string name, value;
};

// How a writer lays out its datasets. large: arrays of more than 4096 values chunked by whole
// rows (about 64k values a chunk), the rest contiguous. every: as the missions' granules, every
// non-empty dataset chunked, min(rows, 10000) rows a chunk (ATL03's and GEDI's 10000), so that
// readers copying a dataset's chunk_dims (rGEDI's and ICESat2VegR's clips) find some. Chunked
// datasets are shuffled and deflated; the values are the same either way.
enum class Hdf5Chunking { large, every };

// A new HDF5 file, written one whole dataset at a time; the groups on a path are made as needed.
// Every failure throws a run Error naming the file and the object.
class Hdf5Writer {
 public:
  // Creates `path`, replacing a file there.
  explicit Hdf5Writer(const std::filesystem::path& path,
                      Hdf5Chunking chunking = Hdf5Chunking::large);
  ~Hdf5Writer();
  Hdf5Writer(const Hdf5Writer&) = delete;
  Hdf5Writer& operator=(const Hdf5Writer&) = delete;

  // `values` laid out C-order over `dims` (one dimension of values.size() when empty). With
  // `fill`, the dataset's fill value and its _FillValue attribute (in the dataset's type).
  // T: double, float, int64, uint64, int32, uint32, uint16, int16, int8, uint8.
  template <typename T>
  void write(const std::string& path, const std::vector<T>& values,
             const std::vector<Hdf5Attribute>& attributes = {},
             const std::vector<std::uint64_t>& dims = {}, std::optional<T> fill = std::nullopt);
  // A one-element dataset of null-terminated fixed-length text.
  void write_text(const std::string& path, const std::string& text,
                  const std::vector<Hdf5Attribute>& attributes = {});
  // A group (and the groups above it); a group that exists is kept.
  void group(const std::string& path);
  // Scalar attributes of an existing object ("/" for the file's own).
  void text_attribute(const std::string& object, const std::string& name, const std::string& value);
  void double_attribute(const std::string& object, const std::string& name, double value);
  // A float64 array attribute, `values` laid out C-order over `dims` (GLAH01's ANCILLARY_DATA
  // sample-location tables).
  void double_array_attribute(const std::string& object, const std::string& name,
                              const std::vector<double>& values,
                              const std::vector<std::uint64_t>& dims);
  // Flushes and closes; throws when the file cannot be completed (a full disk).
  void close();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// What a reader finds at a dataset: its dimensions and the class of what it stores.
struct Hdf5DatasetShape {
  std::vector<std::uint64_t> dims;
  bool numeric = false;  // integers or floating point
  bool integer = false;  // integers (signed or not)
  bool is_signed = false;
};

// An HDF5 file opened to read. Errors say what failed; the caller names the place.
class Hdf5Reader {
 public:
  // Whether `path` is an HDF5 file (false for a file of anything else, or none).
  static bool is_hdf5(const std::filesystem::path& path);
  // Opens `path` read-only; throws an input Error naming it when it cannot.
  explicit Hdf5Reader(const std::filesystem::path& path);
  ~Hdf5Reader();
  Hdf5Reader(const Hdf5Reader&) = delete;
  Hdf5Reader& operator=(const Hdf5Reader&) = delete;

  // Whether every link on `path` exists (a group or a dataset).
  bool has(const std::string& path) const;
  bool is_group(const std::string& path) const;
  // The names of the links in group `path`, in name order.
  std::vector<std::string> children(const std::string& path) const;
  // The dataset's shape; nullopt when `path` is no dataset.
  std::optional<Hdf5DatasetShape> shape(const std::string& path) const;
  // The whole dataset, converted by HDF5 to T (double, int64, uint64); false when the read
  // fails (a truncated or corrupt file). The caller has checked its size with shape().
  template <typename T>
  bool read(const std::string& path, std::vector<T>& values) const;
  // A numeric attribute of `object` ("/" for the file's own) converted to double, C-order over
  // `dims`; false when it is absent, not numeric, holds more than `most` values or cannot be
  // read.
  bool read_attribute(const std::string& object, const std::string& name, std::size_t most,
                      std::vector<double>& values, std::vector<std::uint64_t>& dims) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Turns HDF5's printing of its error stack off for the calling thread, once; call it holding
// libnetcdf's lock (core/netcdf_lock.hpp). Debian's HDF5 keeps that setting per thread and
// libnetcdf turns it off only in the thread that first calls it: in any other, its probes of
// optional attributes on opening a file printed a dozen lines each to stderr (two Python threads
// calling glaswave.run 20 times: 3,300 lines). The writers and readers call it; so do readers of
// the products in other threads (the Python module).
void quiet_hdf5_in_this_thread();

}  // namespace glaswave
