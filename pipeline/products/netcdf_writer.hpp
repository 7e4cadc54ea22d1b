// shots.nc: the waveform product as NetCDF-4, CF-1.10 with featureType "trajectory" (one
// record per shot; PRODUCT.md section 4). Records may be written in any order; the file
// appears under its final name only when finish() succeeds.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>

#include "pipeline/products/product_writer.hpp"
#include "pipeline/products/shot_record.hpp"

namespace glaswave {

// Turns HDF5's printing of its error stack off for the calling thread, once; call it holding
// libnetcdf's lock (core/netcdf_lock.hpp). Debian's HDF5 keeps that setting per thread and
// libnetcdf turns it off only in the thread that first calls it: in any other, its probes of
// optional attributes on opening a file printed a dozen lines each to stderr (two Python threads
// calling glaswave.run 20 times: 3,300 lines). The writer calls it; so do readers of the
// products in other threads (the Python module).
void quiet_hdf5_in_this_thread();

class NetcdfWriter final : public ProductWriter {
 public:
  // Creates final_path + ".part" with every dimension and variable defined and the
  // shot-independent variables (bands, bin times, transmitted pulse) written.
  // Throws Error (run) when the file cannot be created or `info` is inconsistent.
  NetcdfWriter(std::filesystem::path final_path, const RunInfo& info);

  // An unfinished writer is aborted.
  ~NetcdfWriter() override;

  NetcdfWriter(const NetcdfWriter&) = delete;
  NetcdfWriter& operator=(const NetcdfWriter&) = delete;

  // As ProductWriter says. Per-band arrays must match the run's bands and bins; a flagged shot
  // may leave them empty, which leaves fill (NaN) in the file.
  void write(std::int64_t index, const ShotRecord& shot) override;
  // Also writes the run statistics as global attributes.
  void finish(const RunStats& stats) override;
  void abort() noexcept override;

 private:
  struct Impl;
  Impl& impl();  // throws Error (run) after abort()
  std::filesystem::path final_path_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace glaswave
