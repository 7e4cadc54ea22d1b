// ATL08 granules as retrieve's input, through GranuleFile: the ATL08 data dictionary's paths, as
// the real files give them and as glaswave writes them.
#include "pipeline/retrieval/atl08_reader.hpp"

#include <array>
#include <cmath>
#include <limits>
#include <mutex>

#include "core/netcdf_lock.hpp"
#include "pipeline/retrieval/granule_file.hpp"

namespace glaswave {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr const char* kAtl08Kind = "an ICESat-2 ATL08 granule";
// ATL08's fill for float32 (3.4028235e38) read as NaN.
double unfilled(double value) { return std::abs(value) < 1e38 ? value : kNaN; }

}  // namespace

bool is_atl08(const std::filesystem::path& file) {
  std::lock_guard lock(netcdf_library_mutex());
  const Hdf5Reader reader(file);
  for (const char* track : kAtlasTracks)
    if (reader.is_group(std::string(track) + "/land_segments")) return true;
  return false;
}

MeasuredShots read_atl08(const std::filesystem::path& file, std::optional<std::int64_t> first,
                         std::optional<std::int64_t> last) {
  std::lock_guard lock(netcdf_library_mutex());
  const GranuleFile granule(file, kAtl08Kind);
  MeasuredShots out;
  out.band_names = {"532"};
  out.bin_ns = kNaN;
  out.pulse_sigma_ns = kNaN;
  out.atl08 = true;
  out.simulated = false;
  for (const char* track : kAtlasTracks)
    out.simulated = out.simulated ||
                    granule.reader().is_group(std::string(track) + "/land_segments/glaswave_truth");
  for (std::size_t b = 0; b < kAtlasTracks.size(); ++b) {
    const std::string land = std::string(kAtlasTracks[b]) + "/land_segments/";
    if (!granule.reader().is_group(land)) continue;
    const std::vector<std::int64_t> ids =
        granule.read<std::int64_t>(land + "segment_id_beg", std::nullopt);
    const std::size_t n = ids.size();
    const std::vector<double> lat = granule.read<double>(land + "latitude", n),
                              lon = granule.read<double>(land + "longitude", n),
                              height = granule.read<double>(land + "canopy/h_canopy", n),
                              ground = granule.read<double>(land + "terrain/h_te_best_fit", n),
                              canopy = granule.read<double>(land + "canopy/n_ca_photons", n),
                              top = granule.read<double>(land + "canopy/n_toc_photons", n),
                              terrain = granule.read<double>(land + "terrain/n_te_photons", n),
                              id_end = granule.optional(land + "segment_id_end", n),
                              slope = granule.optional(land + "terrain/terrain_slope", n);
    const std::string truth = land + "glaswave_truth/";
    const std::vector<double> cover_true = granule.optional(truth + "canopy_cover", n),
                              pai_true = granule.optional(truth + "pai", n),
                              height_true = granule.optional(truth + "h_canopy", n),
                              ground_true = granule.optional(truth + "h_te", n),
                              pgap_true = granule.optional(truth + "pgap", n);
    const auto count = [](double c) {
      return std::isfinite(c) && c >= 0.0 && c < 2e9 ? static_cast<std::int64_t>(c) : 0;
    };
    for (std::size_t i = 0; i < n; ++i) {
      if ((first && ids[i] < *first) || (last && ids[i] >= *last)) continue;
      MeasuredShot s;
      s.shot_number = ids[i];
      s.beam = static_cast<int>(b) + 1;
      s.lat_deg = unfilled(lat[i]);
      s.lon_deg = unfilled(lon[i]);
      // Without segment_id_end, ATL08's five 20 m segments.
      const double end = std::isfinite(id_end[i]) && id_end[i] >= static_cast<double>(ids[i]) &&
                                 id_end[i] < static_cast<double>(ids[i]) + 1e6
                             ? id_end[i]
                             : static_cast<double>(ids[i] + 4);
      const double rise = unfilled(slope[i]);
      s.segment = Atl08Segment{unfilled(height[i]),
                               unfilled(ground[i]),
                               {count(terrain[i]), count(canopy[i]), count(top[i])},
                               static_cast<std::int64_t>(end),
                               std::isfinite(rise) ? rise : 0.0};
      s.canopy_height_true_m = unfilled(height_true[i]);
      s.cover_true = unfilled(cover_true[i]);
      s.pai_true = unfilled(pai_true[i]);
      s.pgap_true = unfilled(pgap_true[i]);
      s.ground_elevation_true_m = unfilled(ground_true[i]);
      s.rhov_rhog_true = kNaN;
      out.shots.push_back(std::move(s));
    }
  }
  return out;
}

}  // namespace glaswave
