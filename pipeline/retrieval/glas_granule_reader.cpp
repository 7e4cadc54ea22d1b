// GLAS GLAH01 and GLAH14 granules as retrieve's input, through GranuleFile: the paths glaswave's
// writers give them and the GLAS readers open (docs/granules.md).
#include "pipeline/retrieval/glas_granule_reader.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>

#include "core/error.hpp"
#include "core/netcdf_lock.hpp"
#include "pipeline/retrieval/forward_table.hpp"
#include "pipeline/retrieval/granule_file.hpp"

namespace glaswave {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kHalfC_m_per_ns = 0.5 * 299792458.0 * 1e-9;  // range per ns of two-way time
constexpr const char* kGlasKind = "a GLAS GLAH01 or GLAH14 granule";
// A sample-location table larger than this is no GLAS table (544 samples a row, a few rows).
constexpr std::size_t kMostTableValues = 1 << 20;
// i_rec_wf_location_index's fill, GLAS's int8 127: the shot's samples have no times.
constexpr double kNoRow = 127.0;

// GLAS's fill for float64 (1.7976931348623157e308) read as NaN.
double unfilled(double value) { return std::abs(value) < 1e300 ? value : kNaN; }

std::vector<std::int64_t> shot_numbers(const GranuleFile& granule, const std::string& d) {
  const std::vector<std::int64_t> records =
      granule.read<std::int64_t>(d + "Time/i_rec_ndx", std::nullopt);
  const std::vector<std::int64_t> counts =
      granule.read<std::int64_t>(d + "Time/i_shot_count", records.size());
  std::vector<std::int64_t> numbers(records.size());
  for (std::size_t i = 0; i < records.size(); ++i) {
    if (records[i] < 0 || records[i] > std::numeric_limits<std::int32_t>::max() || counts[i] < 1 ||
        counts[i] > 40)
      granule.refuse(d + "Time/i_shot_count", "shot " + std::to_string(i) + " is record " +
                                                  std::to_string(records[i]) + ", shot " +
                                                  std::to_string(counts[i]) +
                                                  " (a GLAS record holds shots 1 to 40)");
    numbers[i] = glas_shot_number(records[i], counts[i]);
  }
  return numbers;
}

}  // namespace

std::int64_t glas_shot_number(std::int64_t rec_ndx, std::int64_t shot_count) {
  return rec_ndx * 40 + shot_count - 1;
}

Glah14Shots read_glah14(const std::filesystem::path& file) {
  std::lock_guard lock(netcdf_library_mutex());
  const GranuleFile granule(file, kGlasKind);
  const std::string d = "Data_40HZ/";
  const std::vector<std::int64_t> numbers = shot_numbers(granule, d);
  const std::size_t n = numbers.size();
  const std::vector<double> lat = granule.read<double>(d + "Geolocation/d_lat", n),
                            lon = granule.read<double>(d + "Geolocation/d_lon", n),
                            elev = granule.read<double>(d + "Elevation_Surfaces/d_elev", n),
                            offset = granule.read<double>(d + "Elevation_Offsets/d_ldRngOff", n),
                            dem = granule.optional(d + "Geophysical/d_DEM_elv", n);
  const std::string truth = d + "glaswave_truth/";
  Glah14Shots out;
  out.simulated = granule.reader().is_group(d + "glaswave_truth");
  const std::vector<double> cover = granule.optional(truth + "cover", n),
                            pai = granule.optional(truth + "pai", n),
                            height = granule.optional(truth + "canopy_height", n),
                            pgap = granule.optional(truth + "pgap", n);
  for (std::size_t i = 0; i < n; ++i) {
    Glah14Shot s;
    s.lat_deg = unfilled(lat[i]);
    // GLAS's longitudes run 0 to 360 east.
    s.lon_deg = unfilled(lon[i]);
    if (s.lon_deg > 180.0) s.lon_deg -= 360.0;
    s.elev_m = unfilled(elev[i]);
    s.land_offset_m = unfilled(offset[i]);
    s.dem_m = unfilled(dem[i]);
    s.cover = unfilled(cover[i]);
    s.pai = unfilled(pai[i]);
    s.canopy_height_m = unfilled(height[i]);
    s.pgap = unfilled(pgap[i]);
    out.shots.emplace_back(numbers[i], s);
  }
  std::sort(out.shots.begin(), out.shots.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  return out;
}

MeasuredShots read_glah01(const std::filesystem::path& file, const Glah14Shots& glah14,
                          std::optional<std::int64_t> first, std::optional<std::int64_t> last) {
  std::lock_guard lock(netcdf_library_mutex());
  const GranuleFile granule(file, kGlasKind);
  const std::string d = "Data_40HZ/";
  const std::vector<std::int64_t> numbers = shot_numbers(granule, d);
  const std::size_t n = numbers.size();
  std::vector<std::uint64_t> dims;
  const std::string wf = d + "Waveform/RecWaveform/r_rng_wf";
  const std::vector<double> rx = granule.read<double>(wf, n, 2, &dims);
  const std::size_t bins = dims[1];
  if (bins < 2) granule.refuse(wf, "has fewer than 2 samples a shot");
  const std::vector<double> noise_mean =
      granule.read<double>(d + "Waveform/Characteristics/d_4nsBgMean", n);
  const std::vector<double> noise_sd =
      granule.read<double>(d + "Waveform/Characteristics/d_4nsBgSDEV", n);
  const std::vector<double> row =
      granule.read<double>(d + "Waveform/RecWaveform/i_rec_wf_location_index", n);
  // The sample times (ns) of each row, from the table the shots' rows index.
  std::vector<double> table;
  std::vector<std::uint64_t> table_dims;
  const char* table_name = "ANCILLARY_DATA/rec_wf_sample_location_table";
  if (!granule.reader().read_attribute("ANCILLARY_DATA", "rec_wf_sample_location_table",
                                       kMostTableValues, table, table_dims))
    granule.refuse(table_name, "missing or not a numeric table (GLAH01 has it)");
  const std::size_t table_columns = table_dims.empty() ? 0 : table_dims.back();
  const std::size_t table_rows = table_columns > 0 ? table.size() / table_columns : 0;
  if (table_columns != bins)
    granule.refuse(table_name, "rows of " + std::to_string(table_columns) +
                                   " sample times where r_rng_wf has " + std::to_string(bins) +
                                   " samples");
  // Each row's even spacing (ns), or NaN for a compressed row.
  std::vector<double> row_step_ns(table_rows, kNaN);
  for (std::size_t r = 0; r < table_rows; ++r) {
    const double* t = &table[r * bins];
    const double step = (t[bins - 1] - t[0]) / static_cast<double>(bins - 1);
    bool even = std::isfinite(step) && step > 0.0;
    for (std::size_t k = 1; even && k < bins; ++k)
      even = std::abs(t[k] - t[k - 1] - step) <= 1e-6 * step;
    if (even) row_step_ns[r] = step;
  }
  double counts_per_W = kNaN;  // glaswave's granule says it; a real one does not
  const std::string truth = d + "glaswave_truth/";
  if (granule.reader().has(truth + "counts_per_watt")) {
    counts_per_W = granule.read<double>(truth + "counts_per_watt", 1)[0];
    if (!(counts_per_W > 0.0) || !std::isfinite(counts_per_W))
      granule.refuse(truth + "counts_per_watt", "not a positive number");
  }
  const bool parts = granule.reader().has(truth + "r_rng_wf_canopy") &&
                     granule.reader().has(truth + "r_rng_wf_ground");
  const std::vector<double> canopy =
      parts ? granule.read<double>(truth + "r_rng_wf_canopy", n, 2) : std::vector<double>{};
  const std::vector<double> ground =
      parts ? granule.read<double>(truth + "r_rng_wf_ground", n, 2) : std::vector<double>{};
  if (parts && (canopy.size() != rx.size() || ground.size() != rx.size()))
    granule.refuse(truth + "r_rng_wf_canopy", "not shaped as r_rng_wf");

  MeasuredShots out;
  out.band_names = {"1064"};  // GLAS's waveform channel, as glaswave's glas preset names it
  out.bin_ns = kNaN;
  out.pulse_sigma_ns = kNaN;
  out.simulated = glah14.simulated;
  for (std::size_t i = 0; i < n; ++i) {
    const std::int64_t number = numbers[i];
    if ((first && number < *first) || (last && number >= *last)) continue;
    MeasuredShot s;
    s.shot_number = number;
    s.beam = 0;
    s.in_counts = true;
    s.counts_per_W = counts_per_W;
    const double r = row[i];
    const bool no_row = r == kNoRow;  // kept, with no estimates
    if (!no_row && (!(r >= 1.0 && r <= static_cast<double>(table_rows)) || r != std::floor(r)))
      granule.refuse(d + "Waveform/RecWaveform/i_rec_wf_location_index",
                     "shot " + std::to_string(number) + "'s row " + std::to_string(r) +
                         " is not one of the table's " + std::to_string(table_rows));
    double step_ns = out.bin_ns;
    if (!no_row) {
      const std::size_t table_row = static_cast<std::size_t>(r) - 1;
      step_ns = row_step_ns[table_row];
      if (!std::isfinite(step_ns))
        granule.refuse(table_name, "row " + std::to_string(table_row + 1) +
                                       " spaces its samples unevenly (a compressed waveform), "
                                       "which retrieve does not read");
      if (!std::isfinite(out.bin_ns)) out.bin_ns = step_ns;
      if (std::abs(step_ns - out.bin_ns) > 1e-6 * out.bin_ns)
        granule.refuse(table_name, "its rows space samples by " + std::to_string(out.bin_ns) +
                                       " and " + std::to_string(step_ns) +
                                       " ns: retrieve reads one spacing a file");
    }
    const auto from = rx.begin() + static_cast<std::ptrdiff_t>(i * bins);
    s.waveform_W.emplace_back(from, from + static_cast<std::ptrdiff_t>(bins));
    s.noise_mean_W = {std::isfinite(unfilled(noise_mean[i])) ? noise_mean[i] : 0.0};
    s.noise_sd_W = {unfilled(noise_sd[i]) > 0.0 ? noise_sd[i] : 0.0};
    const auto match =
        std::lower_bound(glah14.shots.begin(), glah14.shots.end(), number,
                         [](const auto& entry, std::int64_t key) { return entry.first < key; });
    const Glah14Shot* placed =
        match != glah14.shots.end() && match->first == number ? &match->second : nullptr;
    const double last_m = placed ? placed->elev_m + placed->land_offset_m : kNaN;
    s.axis = {step_ns, last_m + kHalfC_m_per_ns * step_ns * static_cast<double>(bins - 1), last_m};
    s.good = !no_row && std::isfinite(last_m);
    for (double x : s.waveform_W.back()) s.good = s.good && std::isfinite(x);
    if (out.simulated && s.good) quiet_monte_carlo_noise(s);
    s.lat_deg = placed ? placed->lat_deg : kNaN;
    s.lon_deg = placed ? placed->lon_deg : kNaN;
    s.canopy_height_true_m = placed ? placed->canopy_height_m : kNaN;
    s.cover_true = placed ? placed->cover : kNaN;
    s.pai_true = placed ? placed->pai : kNaN;
    s.pgap_true = placed ? placed->pgap : kNaN;
    s.ground_elevation_true_m = placed && out.simulated ? placed->dem_m : kNaN;
    s.rhov_rhog_true = kNaN;
    if (parts) {
      double c = 0.0, g = 0.0;
      for (std::size_t k = 0; k < bins; ++k) {
        c += canopy[i * bins + k];
        g += ground[i * bins + k];
      }
      s.rhov_rhog_true = implied_rhov_rhog(c, g, s.cover_true);
    }
    out.shots.push_back(std::move(s));
  }
  if (!std::isfinite(out.bin_ns)) out.bin_ns = table_rows > 0 ? row_step_ns[0] : kNaN;
  return out;
}

}  // namespace glaswave
