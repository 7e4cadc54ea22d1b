// gedi_l2b.h5 in GEDI02_B's layout: the paths and dtypes of the real product (its data
// dictionary; the real subset in rGEDI's inst/extdata), filled from the L2B algorithm's results.
#include "pipeline/retrieval/gedi_l2b_granule.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>

#include "core/atomic_file.hpp"
#include "core/hdf5_file.hpp"
#include "core/netcdf_lock.hpp"
#include "pipeline/products/gedi_granule.hpp"
#include "pipeline/products/hdf5_granule_writer.hpp"

namespace glaswave {
namespace {

double or_fill(double value) { return std::isfinite(value) ? value : kGediL2bFill; }

template <typename T, typename F>
std::vector<T> column(const std::vector<const GediL2bShot*>& shots, F get) {
  std::vector<T> values;
  values.reserve(shots.size());
  for (const GediL2bShot* s : shots) values.push_back(static_cast<T>(get(*s)));
  return values;
}

// Latitude or longitude of the beam's axis at `elevation_m`, linear between bin 0 and the last
// bin (as L1B gives them; the beam is straight over a waveform's tens of metres).
double along_beam(const GediL2bShot& s, double elevation_m, bool latitude) {
  const double top = latitude ? s.info.lat_bin0_deg : s.info.lon_bin0_deg;
  const double bottom = latitude ? s.info.lat_lastbin_deg : s.info.lon_lastbin_deg;
  const double span = s.axis.elev_bin0_m - s.axis.elev_lastbin_m;
  if (!std::isfinite(elevation_m) || !(std::abs(span) > 0.0)) return kGediL2bFill;
  return top + (bottom - top) * (s.axis.elev_bin0_m - elevation_m) / span;
}

bool ran(const GediL2bShot& s) { return s.l2b.algorithmrun_flag != 0; }

// The bins pgap_theta_z covers: from the signal's begin to its end (toploc to botloc, whole
// bins), as the real product's rx_sample_count does (tens of bins, not the L1B window's
// hundreds); none where the algorithm did not run.
std::pair<std::size_t, std::size_t> profile_bins(const GediL2bShot& s) {
  if (!ran(s) || s.bins == 0 || s.l2b.pgap_theta_z.size() != s.bins) return {0, 0};
  const double last = static_cast<double>(s.bins - 1);
  const auto first = static_cast<std::size_t>(std::clamp(std::floor(s.l2a.toploc_bin), 0.0, last));
  const auto end = static_cast<std::size_t>(std::clamp(std::ceil(s.l2a.botloc_bin), 0.0, last)) + 1;
  return {first, std::max(first, end)};
}

void write_beam(Hdf5Writer& f, const std::string& g, const std::vector<const GediL2bShot*>& shots) {
  const std::uint64_t n = shots.size();
  const double fill = kGediL2bFill;
  auto l2b_value = [](double GediL2bResult::*member) {
    return
        [member](const GediL2bShot& s) { return ran(s) ? or_fill(s.l2b.*member) : kGediL2bFill; };
  };
  write_dataset(
      f, g + "/algorithmrun_flag",
      column<std::uint8_t>(shots, [](const GediL2bShot& s) { return s.l2b.algorithmrun_flag; }),
      {"counter", "1 when the L2B algorithm ran on the shot"});
  write_dataset(f, g + "/beam",
                column<std::uint16_t>(shots, [](const GediL2bShot& s) { return s.info.beam; }),
                {"counter", "Beam number"});
  write_dataset(f, g + "/channel",
                column<std::uint8_t>(shots, [](const GediL2bShot& s) { return s.info.channel; }),
                {"counter", "Channel number"});
  write_dataset(f, g + "/cover", column<float>(shots, l2b_value(&GediL2bResult::cover)),
                {"1", "Total canopy cover, 1 - pgap_theta", fill});
  auto profile = [&](std::array<double, kL2bProfileBins> GediL2bResult::*member) {
    std::vector<float> values;
    values.reserve(n * kL2bProfileBins);
    for (const GediL2bShot* s : shots)
      for (double v : s->l2b.*member)
        values.push_back(static_cast<float>(ran(*s) ? or_fill(v) : fill));
    return values;
  };
  const std::vector<std::uint64_t> by_height = {n, static_cast<std::uint64_t>(kL2bProfileBins)};
  write_dataset(f, g + "/cover_z", profile(&GediL2bResult::cover_z),
                {"1", "Cumulative canopy cover above each 5 m height over the ground", fill},
                by_height);
  write_dataset(
      f, g + "/delta_time",
      column<double>(shots, [](const GediL2bShot& s) { return s.info.delta_time_s; }),
      {"seconds since 2018-01-01", "Transmit time of the shot since 2018-01-01T00:00:00Z"});
  write_dataset(f, g + "/fhd_normal", column<float>(shots, l2b_value(&GediL2bResult::fhd_normal)),
                {"1", "Foliage height diversity of the PAVD profile", fill});
  write_dataset(
      f, g + "/l2a_quality_flag",
      column<std::uint8_t>(shots, [](const GediL2bShot& s) { return s.l2a_quality_flag; }),
      {"counter", "L2A's quality flag of the shot"});
  write_dataset(
      f, g + "/l2b_quality_flag",
      column<std::uint8_t>(shots, [](const GediL2bShot& s) { return s.l2b.l2b_quality_flag; }),
      {"counter", "1 for a shot whose L2B metrics are usable"});
  write_dataset(f, g + "/master_frac",
                column<double>(shots,
                               [](const GediL2bShot& s) {
                                 return s.info.delta_time_s - std::floor(s.info.delta_time_s);
                               }),
                {"seconds", "Fractional part of delta_time"});
  write_dataset(f, g + "/master_int",
                column<std::uint32_t>(shots,
                                      [](const GediL2bShot& s) {
                                        return std::max(0.0, std::floor(s.info.delta_time_s));
                                      }),
                {"seconds", "Whole seconds of delta_time"});
  write_dataset(
      f, g + "/num_detectedmodes",
      column<std::uint8_t>(
          shots, [](const GediL2bShot& s) { return std::clamp(s.l2a.num_detectedmodes, 0, 255); }),
      {"counter", "Number of modes the selected L2A group detected"});
  write_dataset(f, g + "/omega", column<float>(shots, l2b_value(&GediL2bResult::omega)),
                {"1", "Foliage clumping index assumed", fill});
  write_dataset(f, g + "/pai", column<float>(shots, l2b_value(&GediL2bResult::pai)),
                {"m^2/m^2", "Total plant area index", fill});
  write_dataset(f, g + "/pai_z", profile(&GediL2bResult::pai_z),
                {"m^2/m^2", "Plant area index above each 5 m height over the ground", fill},
                by_height);
  write_dataset(f, g + "/pavd_z", profile(&GediL2bResult::pavd_z),
                {"m^2/m^3", "Plant area volume density in each 5 m bin over the ground", fill},
                by_height);
  write_dataset(f, g + "/pgap_theta", column<float>(shots, l2b_value(&GediL2bResult::pgap_theta)),
                {"1", "Total gap probability at the beam's angle", fill});
  // pgap_theta_z over each shot's bins from the signal's begin to its end, concatenated.
  std::vector<float> pgap;
  std::vector<std::int64_t> start, count;
  for (const GediL2bShot* s : shots) {
    const auto [first, end] = profile_bins(*s);
    start.push_back(static_cast<std::int64_t>(pgap.size()) + 1);
    count.push_back(static_cast<std::int64_t>(end - first));
    for (std::size_t i = first; i < end; ++i)
      pgap.push_back(static_cast<float>(or_fill(s->l2b.pgap_theta_z[i])));
  }
  write_dataset(
      f, g + "/pgap_theta_z", pgap,
      {"1", "Gap probability at each bin from the signal's begin to its end, concatenated", fill});
  write_dataset(f, g + "/rg", column<float>(shots, l2b_value(&GediL2bResult::rg)),
                {"counts", "Integral of the ground return", fill});
  write_dataset(
      f, g + "/rh100",
      column<std::int16_t>(shots,
                           [](const GediL2bShot& s) {
                             // rh100: the highest return above the ground (L2A's rh100, which the
                             // group's rh_m[100] equals unless an L2A granule gave another ground).
                             const double cm = std::round(
                                 (s.l2a.elev_highestreturn_m - s.l2a.elev_lowestmode_m) * 100.0);
                             return s.l2a.has_ground && std::isfinite(cm) && std::abs(cm) < 32767.0
                                        ? cm
                                        : kGediL2bFill;
                           }),
      {"cm", "Height of the highest return above the lowest mode (L2A's rh100)", fill});
  write_dataset(f, g + "/rhog", column<float>(shots, l2b_value(&GediL2bResult::rhog)),
                {"1", "Ground reflectance assumed", fill});
  write_dataset(f, g + "/rhov", column<float>(shots, l2b_value(&GediL2bResult::rhov)),
                {"1", "Canopy reflectance assumed", fill});
  write_dataset(
      f, g + "/rossg", column<float>(shots, l2b_value(&GediL2bResult::rossg)),
      {"1", "Ross G function assumed: projection of unit foliage area on the beam", fill});
  write_dataset(f, g + "/rv", column<float>(shots, l2b_value(&GediL2bResult::rv)),
                {"counts", "Integral of the canopy return", fill});
  write_dataset(f, g + "/rx_sample_count", count,
                {"counter", "Number of pgap_theta_z samples of the shot"});
  write_dataset(f, g + "/rx_sample_start_index", start,
                {"counter", "Index in pgap_theta_z of the shot's first sample, from 1"});
  write_dataset(
      f, g + "/selected_l2a_algorithm",
      column<std::uint8_t>(shots, [](const GediL2bShot& s) { return s.selected_algorithm; }),
      {"counter", "The L2A setting group (1..6) the L2B algorithm ran on"});
  write_dataset(f, g + "/sensitivity",
                column<float>(shots, [](const GediL2bShot& s) { return or_fill(s.sensitivity); }),
                {"1", "L2A's sensitivity of the shot (fill without an L2A granule)", fill});
  write_dataset(f, g + "/shot_number",
                column<std::uint64_t>(shots, [](const GediL2bShot& s) { return s.shot_number; }),
                {"counter", "Unique shot ID."});

  const std::string geo = g + "/geolocation/";
  write_dataset(
      f, geo + "degrade_flag",
      column<std::int8_t>(shots, [](const GediL2bShot& s) { return s.info.degrade_flag; }),
      {"counter", "L1B's degraded pointing or positioning flag"});
  write_dataset(
      f, geo + "delta_time",
      column<double>(shots, [](const GediL2bShot& s) { return s.info.delta_time_s; }),
      {"seconds since 2018-01-01", "Transmit time of the shot since 2018-01-01T00:00:00Z"});
  write_dataset(f, geo + "digital_elevation_model",
                column<float>(shots, [](const GediL2bShot& s) { return or_fill(s.info.dem_m); }),
                {"meters", "L1B's digital elevation model under the footprint", fill});
  auto l2a_elevation = [](double L2aGroupResult::*member) {
    return [member](const GediL2bShot& s) {
      return s.l2a.has_ground ? or_fill(s.l2a.*member) : kGediL2bFill;
    };
  };
  write_dataset(
      f, geo + "elev_highestreturn",
      column<float>(shots, l2a_elevation(&L2aGroupResult::elev_highestreturn_m)),
      {"meters", "Elevation of the highest detected return above the WGS84 ellipsoid", fill});
  write_dataset(
      f, geo + "elev_lowestmode",
      column<float>(shots, l2a_elevation(&L2aGroupResult::elev_lowestmode_m)),
      {"meters", "Elevation of the center of the lowest mode above the WGS84 ellipsoid", fill});
  write_dataset(f, geo + "elevation_bin0",
                column<double>(shots, [](const GediL2bShot& s) { return s.axis.elev_bin0_m; }),
                {"meters", "Elevation of the waveform's first bin (L1B)"});
  write_dataset(f, geo + "elevation_lastbin",
                column<double>(shots, [](const GediL2bShot& s) { return s.axis.elev_lastbin_m; }),
                {"meters", "Elevation of the waveform's last bin (L1B)"});
  // height_bin0 and height_lastbin: pgap_theta_z's first and last bins above the lowest mode.
  auto profile_height = [](bool top) {
    return [top](const GediL2bShot& s) {
      const auto [first, end] = profile_bins(s);
      if (end == first) return kGediL2bFill;
      const double bin = static_cast<double>(top ? first : end - 1);
      return s.axis.elevation_m(bin, s.bins) - s.l2a.elev_lowestmode_m;
    };
  };
  write_dataset(f, geo + "height_bin0", column<float>(shots, profile_height(true)),
                {"meters", "Height of pgap_theta_z's first bin above the lowest mode", fill});
  write_dataset(f, geo + "height_lastbin", column<float>(shots, profile_height(false)),
                {"meters", "Height of pgap_theta_z's last bin above the lowest mode", fill});
  auto at_return = [](bool lowest, bool latitude) {
    return [lowest, latitude](const GediL2bShot& s) {
      if (!s.l2a.has_ground) return kGediL2bFill;
      return along_beam(s, lowest ? s.l2a.elev_lowestmode_m : s.l2a.elev_highestreturn_m, latitude);
    };
  };
  write_dataset(f, geo + "lat_highestreturn", column<double>(shots, at_return(false, true)),
                {"degrees", "Latitude of the highest detected return", fill});
  write_dataset(f, geo + "lat_lowestmode", column<double>(shots, at_return(true, true)),
                {"degrees", "Latitude of the center of the lowest mode", fill});
  write_dataset(f, geo + "latitude_bin0",
                column<double>(shots, [](const GediL2bShot& s) { return s.info.lat_bin0_deg; }),
                {"degrees", "Latitude of the waveform's first bin (L1B)"});
  write_dataset(f, geo + "latitude_lastbin",
                column<double>(shots, [](const GediL2bShot& s) { return s.info.lat_lastbin_deg; }),
                {"degrees", "Latitude of the waveform's last bin (L1B)"});
  write_dataset(
      f, geo + "local_beam_azimuth",
      column<float>(shots,
                    [](const GediL2bShot& s) { return or_fill(s.info.local_beam_azimuth_rad); }),
      {"radians", "The beam's azimuth, east of north (L1B; fill where L1B has none)", fill});
  write_dataset(
      f, geo + "local_beam_elevation",
      column<float>(shots,
                    [](const GediL2bShot& s) { return or_fill(s.info.local_beam_elevation_rad); }),
      {"radians", "The beam's elevation above the local horizon", fill});
  write_dataset(f, geo + "lon_highestreturn", column<double>(shots, at_return(false, false)),
                {"degrees", "Longitude of the highest detected return", fill});
  write_dataset(f, geo + "lon_lowestmode", column<double>(shots, at_return(true, false)),
                {"degrees", "Longitude of the center of the lowest mode", fill});
  write_dataset(f, geo + "longitude_bin0",
                column<double>(shots, [](const GediL2bShot& s) { return s.info.lon_bin0_deg; }),
                {"degrees", "Longitude of the waveform's first bin (L1B)"});
  write_dataset(f, geo + "longitude_lastbin",
                column<double>(shots, [](const GediL2bShot& s) { return s.info.lon_lastbin_deg; }),
                {"degrees", "Longitude of the waveform's last bin (L1B)"});
  write_dataset(f, geo + "shot_number",
                column<std::uint64_t>(shots, [](const GediL2bShot& s) { return s.shot_number; }),
                {"counter", "Unique shot ID."});
  write_dataset(
      f, geo + "solar_azimuth",
      column<float>(shots, [](const GediL2bShot& s) { return or_fill(s.info.solar_azimuth_deg); }),
      {"degrees", "The sun's azimuth at the footprint (L1B)", fill});
  write_dataset(
      f, geo + "solar_elevation",
      column<float>(shots,
                    [](const GediL2bShot& s) { return or_fill(s.info.solar_elevation_deg); }),
      {"degrees", "The sun's elevation at the footprint (L1B)", fill});

  write_dataset(f, g + "/ancillary/dz", std::vector<double>{kL2bDz_m},
                {"meters", "Height step of the cover_z, pai_z and pavd_z profiles"});
  write_dataset(f, g + "/ancillary/maxheight_cuttoff",
                std::vector<double>{kL2bDz_m * kL2bProfileBins},
                {"meters", "Top of the profiles: their bins times dz"});
}

}  // namespace

std::uint8_t gedi_real_channel(std::uint16_t beam) {
  switch (beam) {
    case 0:
    case 1:
      return 0;
    case 2:
    case 3:
      return 1;
    case 5:
      return 2;
    case 6:
      return 3;
    case 8:
      return 4;
    case 11:
      return 5;
    default:
      return 255;
  }
}

void write_gedi_l2b(const std::filesystem::path& path, const std::vector<GediL2bShot>& shots,
                    const std::string& history) {
  std::map<std::uint16_t, std::vector<const GediL2bShot*>> beams;
  for (const GediL2bShot& s : shots) beams[s.info.beam].push_back(&s);
  AtomicFile file(path);
  {
    std::lock_guard lock(netcdf_library_mutex());
    Hdf5Writer writer(file.part_path(), Hdf5Chunking::every);  // as real L2B
    for (const auto& [beam, members] : beams) {
      const std::string group = gedi_beam_group(beam);
      described_group(writer, group, beam < 4 ? "Coverage beam" : "Full power beam");
      write_beam(writer, group, members);
    }
    described_group(writer, "METADATA/DatasetIdentification");
    writer.text_attribute("METADATA/DatasetIdentification", "shortName", "GEDI_L2B");
    writer.text_attribute("/", "short_name", "GEDI_L2B");
    writer.text_attribute("/", "history", history);
    writer.text_attribute("/", "source",
                          "glaswave retrieve: GEDI L2B's algorithm (Tang & Armston's ATBD) on the "
                          "input's waveforms");
    writer.close();
  }
  file.commit();
}

}  // namespace glaswave
