// shots.nc: the waveform product as NetCDF-4, CF-1.10 with featureType "trajectory" (one
// record per shot; PRODUCT.md section 4). Records may be written in any order; the file
// appears under its final name only when finish() succeeds.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>

#include "core/hdf5_file.hpp"  // quiet_hdf5_in_this_thread, for the products' readers
#include "pipeline/products/product_writer.hpp"
#include "pipeline/products/shot_record.hpp"

namespace glaswave {

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
