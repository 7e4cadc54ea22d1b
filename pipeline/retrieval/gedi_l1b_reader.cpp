// GEDI L1B and L2A granules as retrieve's input, through Hdf5Reader: the GEDI01_B and GEDI02_A
// data dictionaries' paths (LP DAAC), as the real files give them and as glaswave writes them.
#include "pipeline/retrieval/gedi_l1b_reader.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
#include <numbers>
#include <regex>

#include "core/error.hpp"
#include "core/hdf5_file.hpp"
#include "core/netcdf_lock.hpp"
#include "pipeline/retrieval/forward_table.hpp"
#include "pipeline/retrieval/granule_file.hpp"

namespace glaswave {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// GEDI's digitiser samples the received waveform every nanosecond (GEDI01_B dictionary).
constexpr double kGediBinNs = 1.0;
constexpr double kEarthRadius_m = 6371008.8;

bool is_beam(const std::string& name) {
  static const std::regex beam("BEAM[01]{4}");
  return std::regex_match(name, beam);
}

std::uint16_t beam_number(const std::string& group) {
  std::uint16_t beam = 0;
  for (char c : group.substr(4)) beam = static_cast<std::uint16_t>(beam * 2 + (c == '1'));
  return beam;
}

// A GEDI granule's BEAMxxxx groups, in name order.
std::vector<std::string> beams_of(const GranuleFile& granule) {
  std::vector<std::string> out;
  for (const std::string& name : granule.reader().children("/"))
    if (is_beam(name) && granule.reader().is_group(name)) out.push_back(name);
  return out;
}

constexpr const char* kGediKind = "a GEDI L1B or L2A granule";

// The beam's angle from the vertical: from L1B's local_beam_elevation (radians above the local
// horizon) when given, else from the line between bin 0 and the last bin.
double zenith_rad(double local_beam_elevation, double lat0, double lon0, double lat1, double lon1,
                  double elev0, double elev1) {
  if (std::isfinite(local_beam_elevation)) return std::numbers::pi / 2.0 - local_beam_elevation;
  const double deg = std::numbers::pi / 180.0;
  const double north = (lat1 - lat0) * deg * kEarthRadius_m;
  const double east = (lon1 - lon0) * deg * kEarthRadius_m * std::cos(0.5 * (lat0 + lat1) * deg);
  const double horizontal = std::hypot(north, east);
  if (!std::isfinite(horizontal) || !(elev0 - elev1 > 0.0)) return 0.0;
  return std::atan2(horizontal, elev0 - elev1);
}

}  // namespace

namespace {

// Whether a beam of the file holds `dataset`.
bool any_beam_has(const std::filesystem::path& file, const char* dataset) {
  std::lock_guard lock(netcdf_library_mutex());
  const GranuleFile granule(file, kGediKind);
  for (const std::string& beam : beams_of(granule))
    if (granule.reader().has(beam + "/" + dataset)) return true;
  return false;
}

}  // namespace

bool is_gedi_l1b(const std::filesystem::path& file) { return any_beam_has(file, "rxwaveform"); }

bool is_gedi_l2a(const std::filesystem::path& file) {
  return !is_gedi_l1b(file) && any_beam_has(file, "elev_lowestmode");
}

std::vector<std::pair<std::uint64_t, GediL2aShot>> read_gedi_l2a(
    const std::filesystem::path& file) {
  std::lock_guard lock(netcdf_library_mutex());
  const GranuleFile granule(file, kGediKind);
  std::vector<std::pair<std::uint64_t, GediL2aShot>> shots;
  for (const std::string& g : beams_of(granule)) {
    const std::vector<std::uint64_t> numbers =
        granule.read<std::uint64_t>(g + "/shot_number", std::nullopt);
    const std::size_t n = numbers.size();
    const std::vector<double> lowest = granule.read<double>(g + "/elev_lowestmode", n);
    const std::vector<double> highest = granule.read<double>(g + "/elev_highestreturn", n);
    const std::vector<double> quality = granule.read<double>(g + "/quality_flag", n);
    const std::vector<double> sensitivity = granule.optional(g + "/sensitivity", n);
    const std::vector<double> selected = granule.optional(g + "/selected_algorithm", n);
    for (std::size_t i = 0; i < n; ++i) {
      GediL2aShot s;
      s.selected_algorithm =
          selected[i] >= 1.0 && selected[i] <= kL2aGroups ? static_cast<int>(selected[i]) : 0;
      // The product's fill (-9999) is no elevation.
      s.elev_lowestmode_m = lowest[i] > -9000.0 ? lowest[i] : kNaN;
      s.elev_highestreturn_m = highest[i] > -9000.0 ? highest[i] : kNaN;
      s.sensitivity = sensitivity[i] > -9000.0 ? sensitivity[i] : kNaN;
      s.quality_flag = quality[i] == 1.0;
      shots.emplace_back(numbers[i], s);
    }
  }
  std::sort(shots.begin(), shots.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  return shots;
}

MeasuredShots read_gedi_l1b(const std::filesystem::path& file,
                            const std::vector<std::pair<std::uint64_t, GediL2aShot>>& l2a,
                            std::optional<std::int64_t> first, std::optional<std::int64_t> last) {
  std::lock_guard lock(netcdf_library_mutex());
  const GranuleFile granule(file, kGediKind);
  MeasuredShots out;
  out.band_names = {"1064"};  // as glaswave's gedi preset names its band, and so its tables
  out.bin_ns = kGediBinNs;
  out.pulse_sigma_ns = kNaN;
  out.simulated = false;
  out.gedi_l1b = true;
  const std::vector<std::string> beams = beams_of(granule);
  if (beams.empty()) granule.refuse("/", "no BEAMxxxx group");
  for (const std::string& g : beams)
    out.simulated = out.simulated || granule.reader().is_group(g + "/glaswave_truth");
  // glaswave's own granule says its digitiser's scale; a real granule's is unknown (NaN).
  double counts_per_W = kNaN;
  if (granule.reader().has("glaswave_truth/counts_per_watt")) {
    counts_per_W = granule.read<double>("glaswave_truth/counts_per_watt", 1)[0];
    if (!(counts_per_W > 0.0) || !std::isfinite(counts_per_W))
      granule.refuse("glaswave_truth/counts_per_watt", "not a positive number");
  }
  for (const std::string& g : beams) {
    const std::vector<std::uint64_t> numbers =
        granule.read<std::uint64_t>(g + "/shot_number", std::nullopt);
    const std::size_t n = numbers.size();
    // The waveforms' indices first: each must lie inside rxwaveform before any is copied.
    const std::vector<std::uint64_t> start =
        granule.read<std::uint64_t>(g + "/rx_sample_start_index", n);
    const std::vector<std::uint64_t> count = granule.read<std::uint64_t>(g + "/rx_sample_count", n);
    const std::optional<Hdf5DatasetShape> rx_shape = granule.reader().shape(g + "/rxwaveform");
    if (!rx_shape || rx_shape->dims.size() != 1)
      granule.refuse(g + "/rxwaveform", "missing or not one-dimensional");
    const std::uint64_t samples = rx_shape->dims[0];
    for (std::size_t i = 0; i < n; ++i) {
      if (start[i] < 1 || count[i] > samples || start[i] - 1 > samples - count[i])
        granule.refuse(g + "/rx_sample_start_index",
                       "shot " + std::to_string(numbers[i]) + "'s " + std::to_string(count[i]) +
                           " samples from index " + std::to_string(start[i]) +
                           " run past rxwaveform's " + std::to_string(samples));
    }
    const std::vector<double> rx = granule.read<double>(g + "/rxwaveform", samples);
    const std::vector<double> noise_mean = granule.read<double>(g + "/noise_mean_corrected", n);
    const std::vector<double> noise_sd = granule.read<double>(g + "/noise_stddev_corrected", n);
    const std::string geo = g + "/geolocation/";
    const std::vector<double> bin0 = granule.read<double>(geo + "elevation_bin0", n);
    const std::vector<double> lastbin = granule.read<double>(geo + "elevation_lastbin", n);
    const std::vector<double> lat0 = granule.optional(geo + "latitude_bin0", n),
                              lon0 = granule.optional(geo + "longitude_bin0", n),
                              lat1 = granule.optional(geo + "latitude_lastbin", n),
                              lon1 = granule.optional(geo + "longitude_lastbin", n),
                              sun_elevation = granule.optional(geo + "solar_elevation", n),
                              sun_azimuth = granule.optional(geo + "solar_azimuth", n),
                              dem = granule.optional(geo + "digital_elevation_model", n),
                              beam_elevation = granule.optional(geo + "local_beam_elevation", n),
                              beam_azimuth = granule.optional(geo + "local_beam_azimuth", n),
                              beam = granule.optional(g + "/beam", n);
    const std::vector<double> delta_time =
        granule.first_of(g, {"delta_time", "geolocation/delta_time"}, n);
    // degrade_flag from release 2, degrade before (GEDI01_B dictionaries 001 and 002).
    const std::vector<double> degrade =
        granule.first_of(g, {"geolocation/degrade_flag", "geolocation/degrade"}, n);
    const std::string truth = g + "/glaswave_truth/";
    const std::vector<double> cover = granule.optional(truth + "cover", n),
                              pai = granule.optional(truth + "pai", n),
                              height = granule.optional(truth + "canopy_height", n),
                              pgap = granule.optional(truth + "pgap", n),
                              canopy = granule.optional(truth + "rx_energy_canopy", n),
                              ground = granule.optional(truth + "rx_energy_ground", n);
    const std::uint16_t group_beam = beam_number(g);
    const auto fill = [](double v) { return v > -9000.0 ? v : kNaN; };
    for (std::size_t i = 0; i < n; ++i) {
      const auto number = static_cast<std::int64_t>(numbers[i]);
      if ((first && number < *first) || (last && number >= *last)) continue;
      MeasuredShot s;
      s.shot_number = number;
      GediShotInfo& info = s.gedi;
      info.present = true;
      info.beam = std::isfinite(beam[i]) ? static_cast<std::uint16_t>(beam[i]) : group_beam;
      info.channel = gedi_real_channel(info.beam);
      info.delta_time_s = delta_time[i];
      info.lat_bin0_deg = lat0[i];
      info.lon_bin0_deg = lon0[i];
      info.lat_lastbin_deg = lat1[i];
      info.lon_lastbin_deg = lon1[i];
      info.solar_elevation_deg = fill(sun_elevation[i]);
      info.solar_azimuth_deg = fill(sun_azimuth[i]);
      info.dem_m = fill(dem[i]);
      info.local_beam_elevation_rad = fill(beam_elevation[i]);
      info.local_beam_azimuth_rad = fill(beam_azimuth[i]);
      info.degrade_flag = std::isfinite(degrade[i]) ? static_cast<std::int8_t>(degrade[i]) : 0;
      info.l2a_elev_lowestmode_m = info.l2a_elev_highestreturn_m = info.l2a_sensitivity = kNaN;
      const auto match =
          std::lower_bound(l2a.begin(), l2a.end(), numbers[i],
                           [](const auto& entry, std::uint64_t key) { return entry.first < key; });
      if (match != l2a.end() && match->first == numbers[i]) {
        info.has_l2a = true;
        info.l2a_selected_algorithm = match->second.selected_algorithm;
        info.l2a_elev_lowestmode_m = match->second.elev_lowestmode_m;
        info.l2a_elev_highestreturn_m = match->second.elev_highestreturn_m;
        info.l2a_sensitivity = match->second.sensitivity;
        info.l2a_quality_flag = match->second.quality_flag;
      }
      s.beam = info.beam;
      s.lat_deg = 0.5 * (lat0[i] + lat1[i]);
      s.lon_deg = 0.5 * (lon0[i] + lon1[i]);
      s.off_nadir_deg =
          zenith_rad(beam_elevation[i], lat0[i], lon0[i], lat1[i], lon1[i], bin0[i], lastbin[i]) *
          180.0 / std::numbers::pi;
      s.axis = {kGediBinNs, bin0[i], lastbin[i]};
      const auto from = rx.begin() + static_cast<std::ptrdiff_t>(start[i] - 1);
      s.waveform_W.emplace_back(from, from + static_cast<std::ptrdiff_t>(count[i]));
      s.noise_mean_W = {std::isfinite(noise_mean[i]) ? noise_mean[i] : 0.0};
      s.noise_sd_W = {std::isfinite(noise_sd[i]) && noise_sd[i] > 0.0 ? noise_sd[i] : 0.0};
      s.counts_per_W = counts_per_W;
      s.in_counts = true;
      s.good = count[i] >= 2 && std::isfinite(bin0[i]) && std::isfinite(lastbin[i]);
      for (double x : s.waveform_W.back()) s.good = s.good && std::isfinite(x);
      if (out.simulated && s.good) quiet_monte_carlo_noise(s);
      s.canopy_height_true_m = fill(height[i]);
      s.cover_true = fill(cover[i]);
      s.pai_true = fill(pai[i]);
      s.pgap_true = fill(pgap[i]);
      s.ground_elevation_true_m = out.simulated ? fill(dem[i]) : kNaN;
      s.rhov_rhog_true = std::isfinite(canopy[i]) && std::isfinite(ground[i])
                             ? implied_rhov_rhog(fill(canopy[i]), fill(ground[i]), fill(cover[i]))
                             : kNaN;
      out.shots.push_back(std::move(s));
    }
  }
  return out;
}

L2aGroupResult gedi_l2a_choice(const L2aResult& result, const GediShotInfo& info, int& selected) {
  selected = result.selected_algorithm;
  if (!info.has_l2a) return result.selected();
  if (info.l2a_selected_algorithm >= 1 && info.l2a_selected_algorithm <= kL2aGroups)
    selected = info.l2a_selected_algorithm;
  L2aGroupResult chosen = selected >= 1 ? result.groups[selected - 1] : result.groups[0];
  // The granule's ground and highest return are the product's; glaswave's group gives the
  // signal's end, which L2A's top level does not carry.
  if (chosen.signal && std::isfinite(info.l2a_elev_lowestmode_m)) {
    chosen.elev_lowestmode_m = info.l2a_elev_lowestmode_m;
    chosen.has_ground = true;
    if (std::isfinite(info.l2a_elev_highestreturn_m))
      chosen.elev_highestreturn_m = info.l2a_elev_highestreturn_m;
  }
  return chosen;
}

}  // namespace glaswave
