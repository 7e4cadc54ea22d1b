// The HDF5 granule writers' shared parts, over the one HDF5 layer (core/hdf5_file.hpp).
#include "pipeline/products/hdf5_granule_writer.hpp"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <numeric>

#include "core/error.hpp"
#include "core/netcdf_lock.hpp"

namespace glaswave {
void described_group(Hdf5Writer& file, const std::string& path, const char* description) {
  file.group(path);
  if (description) file.text_attribute(path, "description", description);
}

std::size_t nearest_band(const RunInfo& info, double wavelength_nm) {
  std::size_t best = 0;
  for (std::size_t b = 1; b < info.bands.size(); ++b)
    if (std::abs(info.bands[b].wavelength_nm - wavelength_nm) <
        std::abs(info.bands[best].wavelength_nm - wavelength_nm))
      best = b;
  return best;
}

std::vector<float> to_counts(const std::vector<double>& power_W, double counts_per_W) {
  std::vector<float> counts(power_W.size());
  for (std::size_t i = 0; i < power_W.size(); ++i)
    counts[i] = static_cast<float>(power_W[i] * counts_per_W);
  return counts;
}

WaveformNoise waveform_noise(const std::vector<float>& counts, double elev_bin0_m,
                             double elev_lastbin_m, double signal_begin_m) {
  const std::size_t n = counts.size();
  if (n == 0) return {};
  std::size_t noise_bins = std::max<std::size_t>(std::min<std::size_t>(8, n), n / 8);
  if (std::isfinite(signal_begin_m) && n > 1) {
    const double step_m = (elev_bin0_m - elev_lastbin_m) / static_cast<double>(n - 1);
    if (step_m > 0) {
      const double before = std::floor((elev_bin0_m - signal_begin_m) / step_m);
      if (before >= 8) noise_bins = static_cast<std::size_t>(std::min<double>(before, n));
    }
  }
  double sum = 0.0;
  for (std::size_t i = 0; i < noise_bins; ++i) sum += counts[i];
  const double mean = sum / static_cast<double>(noise_bins);
  double squares = 0.0;
  for (std::size_t i = 0; i < noise_bins; ++i) squares += (counts[i] - mean) * (counts[i] - mean);
  return {mean, std::sqrt(squares / static_cast<double>(noise_bins))};
}

LatLon beam_point(const ShotRecord& shot, double elevation_m) {
  const double rise_m = shot.sc_alt_m - shot.elev_m;
  if (!std::isfinite(elevation_m) || !std::isfinite(shot.elev_m) || !(rise_m > 0))
    return {shot.lat_deg, shot.lon_deg};
  const double t = (elevation_m - shot.elev_m) / rise_m;
  double dlon = shot.sc_lon_deg - shot.lon_deg;
  if (dlon > 180) dlon -= 360;
  if (dlon < -180) dlon += 360;
  return {shot.lat_deg + t * (shot.sc_lat_deg - shot.lat_deg), shot.lon_deg + t * dlon};
}

Hdf5GranuleWriter::Hdf5GranuleWriter(const std::filesystem::path& final_path, const RunInfo& info)
    : info_(info), file_(final_path), written_(static_cast<std::size_t>(info.shots), false) {}

Hdf5GranuleWriter::~Hdf5GranuleWriter() = default;

void Hdf5GranuleWriter::write(std::int64_t index, const ShotRecord& shot) {
  if (done_) throw run_error(file_.final_path().string(), "a record after the product ended");
  if (index < 0 || index >= info_.shots || written_[static_cast<std::size_t>(index)])
    throw run_error(file_.final_path().string(),
                    "record " + std::to_string(index) + " out of range or written twice");
  keep(index, shot);
  written_[static_cast<std::size_t>(index)] = true;
}

void Hdf5GranuleWriter::finish(const RunStats&) {
  if (std::find(written_.begin(), written_.end(), false) != written_.end())
    throw run_error(file_.final_path().string(), "a record was never written");
  {
    // libhdf5 is libnetcdf's too, and neither is thread-safe: one lock for both.
    std::lock_guard lock(netcdf_library_mutex());
    Hdf5Writer file(file_.part_path(), chunking());
    write_file(file);
    file.close();
  }
  file_.commit();
  done_ = true;
}

void Hdf5GranuleWriter::abort() noexcept {
  done_ = true;
  std::error_code ignored;
  std::filesystem::remove(file_.part_path(), ignored);
}

}  // namespace glaswave
