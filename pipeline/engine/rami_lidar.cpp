// ROMC's lidar format (RAMI-IV, "lidar_tot"): a header line (rows, columns, the height interval),
// then one row a height bin from the ground up: the bin's mean height (m), the return signal and
// its standard deviation (-1 when not available). RAMI-IV's measurement: a delta pulse lighting a
// 50 m disc uniformly at nadir; lidar_sgl_co keeps the light scattered once, lidar_tot all of it.
#include "pipeline/engine/rami_lidar.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "pipeline/engine/rami_measurements.hpp"
#include "pipeline/shot/footprint_geometry.hpp"

namespace glaswave {
namespace {

class RamiLidarWriter final : public ProductWriter {
 public:
  RamiLidarWriter(std::filesystem::path dir, const Config& config, const RunInfo& info)
      : dir_(std::move(dir)),
        rami_(*config.output.rami),
        bands_(config.sensor.bands),
        bin_time_ns_(info.bin_time_ns),
        bin_s_(config.sensor.bin_ns * 1e-9),
        telescope_area_m2_(config.sensor.telescope_area_m2),
        fov_fraction_(beam_fraction_in_view(config.sensor)),
        ledger_(dir_, info.shots),
        sums_(rami_.measurements.size() * bands_.size()),
        squares_(sums_.size()) {}

  void write(std::int64_t index, const ShotRecord& shot) override {
    ledger_.check_write(index);
    ledger_.taken(index);
    // A shot off the terrain has no waveform to bin.
    if (shot.quality_flag != quality_good || shot.rx_waveform_W.empty() ||
        std::isnan(shot.rx_waveform_W[0][0]))
      return;
    ++shots_;
    const double cos_nadir = std::cos(shot.off_nadir_deg * std::numbers::pi / 180.0);
    for (std::size_t m = 0; m < rami_.measurements.size(); ++m)
      for (std::size_t band = 0; band < bands_.size(); ++band) {
        const bool once = rami_.measurements[m] == "lidar_sgl_co";
        if (once && shot.rx_waveform_order_W.at(band).empty())
          throw run_error(dir_.string(), "lidar_sgl_co needs the per-order waveforms");
        const std::vector<double>& power_W =
            once ? shot.rx_waveform_order_W[band][0] : shot.rx_waveform_W[band];
        // PHYSICS.md section 3's normalisation: E_t T A_T f_fov / (pi R^2), the return of a
        // white Lambertian ground square-on; the rows then sum to an apparent reflectance.
        const LidarBand& b = bands_[band];
        const double unit_J = b.pulse_energy_mJ * 1e-3 * b.atmos_transmission_roundtrip *
                              telescope_area_m2_ * fov_fraction_ /
                              (std::numbers::pi * shot.range_m * shot.range_m);
        std::vector<double> rows;
        for (std::size_t i = 0; i < power_W.size(); ++i) {
          // The bin's height along the vertical, from its two-way time after the ground's
          // return at the footprint centre. Window bins are centred on the rows' edges (the
          // ground's on 0): one goes whole to the row below its centre, so that a canopy's top
          // ends in its own row, and the ground's to the first. Light later than the ground's
          // (below it) is in no row.
          const double height_m = -0.5 * speed_of_light_m_s * bin_time_ns_[i] * 1e-9 * cos_nadir;
          const double row = std::max(0.0, std::ceil(height_m / rami_.height_bin_m - 1e-6) - 1.0);
          if (height_m < -1e-6 * rami_.height_bin_m || power_W[i] == 0.0) continue;
          const auto r = static_cast<std::size_t>(row);
          if (rows.size() <= r) rows.resize(r + 1, 0.0);
          rows[r] += power_W[i] * bin_s_ / unit_J;
        }
        std::vector<double>& sum = sums_[m * bands_.size() + band];
        std::vector<double>& square = squares_[m * bands_.size() + band];
        if (sum.size() < rows.size()) {
          sum.resize(rows.size(), 0.0);
          square.resize(rows.size(), 0.0);
        }
        for (std::size_t r = 0; r < rows.size(); ++r) {
          sum[r] += rows[r];
          square[r] += rows[r] * rows[r];
        }
      }
  }

  void finish(const RunStats&) override {
    ledger_.check_finish();
    if (shots_ == 0)
      throw run_error(dir_.string(), "no shot of the run had a waveform to bin for RAMI");
    // Up to the highest row any measurement scored into: the pulse kernel's far tail (e^-500 of
    // a delta pulse's neighbour bins) is no return.
    double largest = 0.0;
    for (const auto& sum : sums_)
      for (double value : sum) largest = std::max(largest, value);
    std::size_t rows = 1;
    for (const auto& sum : sums_)
      for (std::size_t r = 0; r < sum.size(); ++r)
        if (sum[r] > 1e-12 * largest) rows = std::max(rows, r + 1);
    std::filesystem::create_directories(dir_);
    const auto n = static_cast<double>(shots_);
    for (std::size_t m = 0; m < rami_.measurements.size(); ++m)
      for (std::size_t band = 0; band < bands_.size(); ++band) {
        const std::vector<double>& sum = sums_[m * bands_.size() + band];
        const std::vector<double>& square = squares_[m * bands_.size() + band];
        char line[160];
        std::snprintf(line, sizeof line, "%4zu %4d %.10f\n", rows, 3, rami_.height_bin_m);
        std::string text = line;
        for (std::size_t r = 0; r < rows; ++r) {
          const double total = r < sum.size() ? sum[r] : 0.0;
          const double mean = total / n;
          // The standard error of the mean over the shots (each shot's own draws), where there
          // are two or more.
          double error = -1.0;
          if (shots_ > 1) {
            const double spread =
                std::max((r < square.size() ? square[r] : 0.0) - total * mean, 0.0);
            error = std::sqrt(spread / (n * (n - 1.0)));
          }
          std::snprintf(line, sizeof line, "%.6f %.10f %.10f\n", (r + 0.5) * rami_.height_bin_m,
                        mean, error);
          text += line;
        }
        write_text_atomically(
            dir_ / rami_file_name(rami_.model.empty() ? "glaswave" : rami_.model, rami_.experiment,
                                  rami_.measurements[m], bands_[band].name),
            text);
      }
    ledger_.finish();
  }

  void abort() noexcept override {}

 private:
  std::filesystem::path dir_;
  RamiLidarSettings rami_;
  std::vector<LidarBand> bands_;
  std::vector<double> bin_time_ns_;
  double bin_s_, telescope_area_m2_, fov_fraction_;
  RecordLedger ledger_;
  std::int64_t shots_ = 0;
  // [measurement * bands + band][row]: the rows' sums over the shots and their squares.
  std::vector<std::vector<double>> sums_, squares_;
};

}  // namespace

std::unique_ptr<ProductWriter> make_rami_lidar_writer(const std::filesystem::path& out_dir,
                                                      const Config& config, const RunInfo& info) {
  return std::make_unique<RamiLidarWriter>(out_dir / "rami", config, info);
}

}  // namespace glaswave
