// What the HDF5 granule writers (GEDI L1B/L2A-style, GLAS GLAH01/GLAH14-style) share: their
// datasets' attributes as the dictionaries give them, and a ProductWriter that keeps each
// shot's few values (a waveform as float32) until finish(), then writes the file under
// FINAL.part and renames it (core/atomic_file.hpp). Records reach writers in shot order, so
// the granule of a resumed or an MPI run is the same bits as an uninterrupted one's.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/atomic_file.hpp"
#include "core/hdf5_file.hpp"
#include "pipeline/products/product_writer.hpp"
#include "pipeline/products/shot_record.hpp"

namespace glaswave {

// The attributes a dataset carries, as the GEDI and GLAS dictionaries give them.
struct Hdf5Attributes {
  Hdf5Attributes(const char* units_ = nullptr, const char* description_ = nullptr,
                 std::optional<double> fill_ = std::nullopt)
      : units(units_), description(description_), fill(fill_) {}
  const char* units;
  const char* description;
  std::optional<double> fill;  // _FillValue, in the dataset's own type
};

// Writes a dataset with the GEDI and GLAS dictionaries' attributes through the one HDF5 layer
// (core/hdf5_file.hpp). T: double, float, uint64, int32, uint16, int16, uint8.
template <typename T>
void write_dataset(Hdf5Writer& file, const std::string& path, const std::vector<T>& values,
                   const Hdf5Attributes& attrs, const std::vector<std::uint64_t>& dims = {}) {
  std::vector<Hdf5Attribute> text;
  if (attrs.units) text.push_back({"units", attrs.units});
  if (attrs.description) text.push_back({"description", attrs.description});
  std::optional<T> fill;
  if (attrs.fill) fill = static_cast<T>(*attrs.fill);
  file.write(path, values, text, dims, fill);
}

// A group with its description.
void described_group(Hdf5Writer& file, const std::string& path, const char* description = nullptr);

// The band a single-band product takes from a run: the one nearest `wavelength_nm`.
std::size_t nearest_band(const RunInfo& info, double wavelength_nm);

// A received waveform as a digitiser gives it: power (W) times `counts_per_W` (RunInfo), as
// float32.
std::vector<float> to_counts(const std::vector<double>& power_W, double counts_per_W);

// The noise of a recorded waveform in counts, as GEDI L1B's noise_mean_corrected and
// noise_stddev_corrected: mean and standard deviation over the bins recorded before the signal
// begins (elevation above `signal_begin_m`), at least 8 of them; without a signal begin, over
// the first eighth of the window (at least 8 bins).
struct WaveformNoise {
  double mean = 0.0, stddev = 0.0;
};
WaveformNoise waveform_noise(const std::vector<float>& counts, double elev_bin0_m,
                             double elev_lastbin_m, double signal_begin_m);

// Latitude and longitude of the point of a shot's beam axis at `elevation_m`, between the
// footprint centre and the spacecraft (linear in latitude, longitude and height: within a
// centimetre for a beam a few degrees off nadir over the tens of metres of a waveform).
struct LatLon {
  double lat_deg, lon_deg;
};
LatLon beam_point(const ShotRecord& shot, double elevation_m);

class Hdf5GranuleWriter : public ProductWriter {
 public:
  Hdf5GranuleWriter(const std::filesystem::path& final_path, const RunInfo& info);
  ~Hdf5GranuleWriter() override;

  void write(std::int64_t index, const ShotRecord& shot) override;
  void finish(const RunStats& stats) override;
  void abort() noexcept override;

 protected:
  // What the granule keeps of a shot (a copy of its record, its waveforms as float32 counts).
  virtual void keep(std::int64_t index, const ShotRecord& shot) = 0;
  // Writes every dataset; `file` is closed and renamed after.
  virtual void write_file(Hdf5Writer& file) = 0;
  // The datasets' layout (GEDI's granules chunk every one, as the real ones).
  virtual Hdf5Chunking chunking() const { return Hdf5Chunking::large; }

  const RunInfo& info() const { return info_; }

 private:
  RunInfo info_;
  AtomicFile file_;
  std::vector<bool> written_;
  bool done_ = false;
};

}  // namespace glaswave
