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

namespace glaswave {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// GEDI's digitiser samples the received waveform every nanosecond (GEDI01_B dictionary).
constexpr double kGediBinNs = 1.0;
// deflate compresses at most 1032 to 1: a dataset declaring more values than that ratio allows
// for the file's bytes is not stored in it, and is refused before anything is allocated.
constexpr double kMostDeflateRatio = 1032.0;
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

// One granule open to read: every dataset checked (present, numeric, its shape) before it is
// read, every refusal one line naming the file and the dataset.
class Granule {
 public:
  explicit Granule(const std::filesystem::path& file)
      : reader_(file), place_(file.string()), bytes_(file_bytes(file)) {}

  const Hdf5Reader& reader() const { return reader_; }
  const std::string& place() const { return place_; }

  std::vector<std::string> beams() const {
    std::vector<std::string> out;
    for (const std::string& name : reader_.children("/"))
      if (is_beam(name) && reader_.is_group(name)) out.push_back(name);
    return out;
  }

  [[noreturn]] void refuse(const std::string& dataset, const std::string& why) const {
    throw input_error(place_, dataset + ": " + why);
  }

  // A one-dimensional numeric dataset of `count` values (any count when nullopt).
  template <typename T>
  std::vector<T> read(const std::string& dataset, std::optional<std::size_t> count) const {
    const std::optional<Hdf5DatasetShape> shape = reader_.shape(dataset);
    if (!shape) refuse(dataset, "missing (a GEDI L1B or L2A granule has it)");
    if (!shape->numeric) refuse(dataset, "not numeric");
    if (shape->dims.size() != 1) refuse(dataset, "not one-dimensional");
    if (count && shape->dims[0] != *count)
      refuse(dataset, std::to_string(shape->dims[0]) + " values where the beam has " +
                          std::to_string(*count) + " shots");
    if (static_cast<double>(shape->dims[0]) > kMostDeflateRatio * static_cast<double>(bytes_) + 1e6)
      refuse(dataset, "declares " + std::to_string(shape->dims[0]) +
                          " values, more than a file of " + std::to_string(bytes_) +
                          " bytes can hold");
    std::vector<T> values;
    if (!reader_.read(dataset, values)) refuse(dataset, "cannot be read (a truncated file?)");
    return values;
  }

  // As read(), NaN everywhere when the dataset is absent.
  std::vector<double> optional(const std::string& dataset, std::size_t count) const {
    if (!reader_.has(dataset)) return std::vector<double>(count, kNaN);
    return read<double>(dataset, count);
  }
  // The first of `names` present (the names of one field in different product releases).
  std::vector<double> first_of(const std::string& group, std::initializer_list<const char*> names,
                               std::size_t count) const {
    for (const char* name : names)
      if (reader_.has(group + "/" + name)) return read<double>(group + "/" + name, count);
    return std::vector<double>(count, kNaN);
  }

 private:
  static std::uintmax_t file_bytes(const std::filesystem::path& file) {
    std::error_code error;
    const std::uintmax_t bytes = std::filesystem::file_size(file, error);
    return error ? 0 : bytes;
  }
  Hdf5Reader reader_;
  std::string place_;
  std::uintmax_t bytes_;
};

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

RetrieveInputKind retrieve_input_kind(const std::filesystem::path& file) {
  std::lock_guard lock(netcdf_library_mutex());
  if (!Hdf5Reader::is_hdf5(file)) return RetrieveInputKind::shots_nc;
  const Granule granule(file);
  bool l2a = false;
  for (const std::string& beam : granule.beams()) {
    if (granule.reader().has(beam + "/rxwaveform")) return RetrieveInputKind::gedi_l1b;
    l2a = l2a || granule.reader().has(beam + "/elev_lowestmode");
  }
  return l2a ? RetrieveInputKind::gedi_l2a : RetrieveInputKind::shots_nc;
}

std::vector<std::pair<std::uint64_t, GediL2aShot>> read_gedi_l2a(
    const std::filesystem::path& file) {
  std::lock_guard lock(netcdf_library_mutex());
  const Granule granule(file);
  std::vector<std::pair<std::uint64_t, GediL2aShot>> shots;
  for (const std::string& g : granule.beams()) {
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
  const Granule granule(file);
  MeasuredShots out;
  out.band_names = {"1064nm"};
  out.bin_ns = kGediBinNs;
  out.pulse_sigma_ns = kNaN;
  out.simulated = false;
  out.gedi_l1b = true;
  const std::vector<std::string> beams = granule.beams();
  if (beams.empty()) granule.refuse("/", "no BEAMxxxx group");
  for (const std::string& g : beams)
    out.simulated = out.simulated || granule.reader().is_group(g + "/glaswave_truth");
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
      s.good = count[i] >= 2 && std::isfinite(bin0[i]) && std::isfinite(lastbin[i]);
      for (double x : s.waveform_W.back()) s.good = s.good && std::isfinite(x);
      // glaswave's granule of a run without a detector: its "noise" is the Monte Carlo's few
      // rays before the signal (a sd of 1e-5 of the peak), which L2A's thresholds would take for
      // a detector's and so find the ground among lone rays far below. Under 1e-3 of the peak
      // (no detector is that quiet) it is none, as in shots.nc without a detector.
      if (out.simulated && s.good) {
        const std::vector<double>& w = s.waveform_W.back();
        const double peak = *std::max_element(w.begin(), w.end()) - s.noise_mean_W[0];
        if (s.noise_sd_W[0] < 1e-3 * peak) s.noise_mean_W[0] = s.noise_sd_W[0] = 0.0;
      }
      s.canopy_height_true_m = fill(height[i]);
      s.cover_true = fill(cover[i]);
      s.pai_true = fill(pai[i]);
      s.ground_elevation_true_m = out.simulated ? fill(dem[i]) : kNaN;
      s.rhov_rhog_true = std::isfinite(canopy[i]) && std::isfinite(ground[i])
                             ? implied_rhov_rhog(fill(canopy[i]), fill(ground[i]), fill(cover[i]))
                             : kNaN;
      out.shots.push_back(std::move(s));
    }
  }
  return out;
}

MeasuredShots read_retrieve_inputs(const std::vector<std::filesystem::path>& inputs,
                                   std::optional<std::int64_t> first,
                                   std::optional<std::int64_t> last) {
  std::vector<RetrieveInputKind> kinds;
  std::vector<std::pair<std::uint64_t, GediL2aShot>> l2a;
  for (const std::filesystem::path& file : inputs) {
    kinds.push_back(retrieve_input_kind(file));
    if (kinds.back() != RetrieveInputKind::gedi_l2a) continue;
    auto more = read_gedi_l2a(file);
    l2a.insert(l2a.end(), more.begin(), more.end());
  }
  std::sort(l2a.begin(), l2a.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  const bool any_l1b =
      std::find(kinds.begin(), kinds.end(), RetrieveInputKind::gedi_l1b) != kinds.end();
  MeasuredShots input;
  bool empty = true;
  for (std::size_t k = 0; k < inputs.size(); ++k) {
    const std::filesystem::path& file = inputs[k];
    if (kinds[k] == RetrieveInputKind::gedi_l2a) {
      if (!any_l1b)
        throw input_error(file.string(),
                          "a GEDI L2A granule is read beside its L1B granule: give the L1B too");
      continue;
    }
    MeasuredShots more = kinds[k] == RetrieveInputKind::gedi_l1b
                             ? read_gedi_l1b(file, l2a, first, last)
                             : read_shots(file, first, last);
    if (empty) {
      input = std::move(more);
      empty = false;
      continue;
    }
    if (more.band_names != input.band_names || more.bin_ns != input.bin_ns)
      throw input_error(file.string(),
                        "its bands or bins are not those of " + inputs.front().string());
    input.simulated = input.simulated && more.simulated;
    for (MeasuredShot& s : more.shots) input.shots.push_back(std::move(s));
  }
  return input;
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
