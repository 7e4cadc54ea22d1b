// The ICESat-2 granules' writer: records kept by index, the beam built and written at the end.
#include "pipeline/products/icesat2_writer.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/error.hpp"
#include "core/registry.hpp"

namespace glaswave {
namespace {

constexpr double wgs84_a_m = 6378137.0, wgs84_e2 = 6.69437999014e-3;

// The distance between two footprints on the WGS84 ellipsoid, from the radii of curvature at
// their mean latitude (meridian M, prime vertical N): over the 0.7 m between ATLAS's shots it is
// the geodesic's to a part in a million, where the mean sphere's would be 0.2 % off at mid
// latitudes (M is 6356 km at 34 N, the mean radius 6371 km).
double distance_m(const BeamShot& a, const BeamShot& b) {
  const double to_rad = std::numbers::pi / 180.0;
  const double sin_lat = std::sin(0.5 * (a.lat_deg + b.lat_deg) * to_rad);
  const double w2 = 1.0 - wgs84_e2 * sin_lat * sin_lat;
  const double m = wgs84_a_m * (1.0 - wgs84_e2) / (w2 * std::sqrt(w2));
  const double n = wgs84_a_m / std::sqrt(w2);
  const double north = m * (b.lat_deg - a.lat_deg) * to_rad;
  const double east = n * std::sqrt(1.0 - sin_lat * sin_lat) *
                      std::remainder(b.lon_deg - a.lon_deg, 360.0) * to_rad;
  return std::hypot(north, east);
}

}  // namespace

Icesat2Writer::Icesat2Writer(const std::filesystem::path& out_dir,
                             const Icesat2ProductSettings& settings, const RunInfo& info)
    : out_dir_(out_dir),
      settings_(settings),
      info_{info.command_line,
            info.config_json,
            settings.sc_orient,
            settings.dead_time_ns,
            info.tx_time_ns,
            info.tx_waveform_W.empty() ? std::vector<double>{} : info.tx_waveform_W.front(),
            settings.cloud_layers},
      shots_(info.shots) {
  if (info.bin_time_ns.size() >= 2) {
    const double bin_ns = info.bin_time_ns[1] - info.bin_time_ns[0];
    window_start_ns_ = info.bin_time_ns.front() - 0.5 * bin_ns;
    window_ns_ = bin_ns * static_cast<double>(info.bin_time_ns.size());
  }
}

void Icesat2Writer::estimate_background(std::vector<BeamShot>& shots,
                                        const std::vector<double>& below) const {
  constexpr std::size_t reach = 500;
  std::vector<double> sum(below.size() + 1, 0.0);
  for (std::size_t k = 0; k < below.size(); ++k) sum[k + 1] = sum[k] + below[k];
  const double slice_s = 0.2 * window_ns_ * 1e-9;
  for (std::size_t k = 0; k < shots.size(); ++k) {
    const std::size_t from = k > reach ? k - reach : 0, to = std::min(shots.size(), k + reach + 1);
    shots[k].background_rate_Hz =
        slice_s > 0.0 ? (sum[to] - sum[from]) / (static_cast<double>(to - from) * slice_s) : 0.0;
  }
}

void Icesat2Writer::write(std::int64_t index, const ShotRecord& shot) {
  if (done_) throw run_error(out_dir_.string(), "ICESat-2 granules: a record after the end");
  if (index < 0 || index >= shots_ || kept_.count(index))
    throw run_error(out_dir_.string(), "ICESat-2 granules: record " + std::to_string(index) +
                                           " out of range or written twice");
  Kept kept;
  kept.beam = shot.beam;
  kept.shot.lat_deg = shot.lat_deg;
  kept.shot.lon_deg = shot.lon_deg;
  kept.shot.delta_time_s = shot.time_s - atlas_epoch_since_glas_epoch_s;
  kept.shot.ground_h_m = shot.elev_m;
  kept.shot.canopy_height_m = shot.canopy_height_true_m;
  kept.shot.canopy_cover = shot.cover_true;
  kept.shot.pai = shot.pai_true;
  kept.shot.pgap = shot.pgap_true;
  kept.shot.solar_elevation_deg = shot.solar_elevation_deg;
  kept.shot.solar_azimuth_deg = shot.solar_azimuth_deg;
  kept.shot.sc_lat_deg = shot.sc_lat_deg;
  kept.shot.sc_lon_deg = shot.sc_lon_deg;
  kept.shot.sc_alt_m = shot.sc_alt_m;
  kept.shot.range_m = shot.range_m;
  const double lowest_fifth_ns = window_start_ns_ + 0.8 * window_ns_;
  for (const double t : shot.photon_time_ns)
    if (t >= lowest_fifth_ns) kept.below_ground += 1.0;
  for (std::size_t i = 0; i < shot.photon_time_ns.size(); ++i) {
    BeamPhoton p;
    p.h_m = shot.photon_h_m[i];
    p.lat_deg = shot.photon_lat_deg[i];
    p.lon_deg = shot.photon_lon_deg[i];
    // ATL03's heights/delta_time is the transmit time of the photon's pulse ("multiple received
    // photons associated with a single transmit pulse will have the same delta_time", the ATL03
    // data dictionary), the shot's; the 3.3 ms of flight are in no ATL03 time.
    p.delta_time_s = kept.shot.delta_time_s;
    p.truth_class = static_cast<std::uint8_t>(shot.photon_class[i]);
    p.order = i < shot.photon_order.size() ? static_cast<std::uint8_t>(shot.photon_order[i]) : 0;
    kept.photons.push_back(p);
  }
  kept_.emplace(index, std::move(kept));
}

BeamTrack Icesat2Writer::gather_beam(const GranuleBeam& granule_beam) const {
  BeamTrack beam;
  beam.name = granule_beam.name;
  beam.strong = granule_beam.strong;
  beam.spot_number = granule_beam.spot_number;
  beam.across_m = granule_beam.across_m;
  beam.pulse_energy_J = granule_beam.pulse_energy_J;
  beam.photons_per_J = granule_beam.photons_per_J;
  const bool every_record = settings_.beams.size() == 1;
  std::vector<double> below;
  for (const auto& [index, kept] : kept_) {
    if (!every_record && kept.beam != granule_beam.spot_number) continue;
    // Shots off the terrain have no position: they are left out of the granules.
    if (!std::isfinite(kept.shot.lat_deg) || !std::isfinite(kept.shot.lon_deg)) continue;
    BeamShot shot = kept.shot;
    shot.along_m =
        beam.shots.empty() ? 0.0 : beam.shots.back().along_m + distance_m(beam.shots.back(), shot);
    shot.first_photon = static_cast<std::uint32_t>(beam.photons.size());
    shot.photon_count = static_cast<std::uint32_t>(kept.photons.size());
    beam.shots.push_back(shot);
    below.push_back(kept.below_ground);
    beam.photons.insert(beam.photons.end(), kept.photons.begin(), kept.photons.end());
  }
  estimate_background(beam.shots, below);
  return beam;
}

void Icesat2Writer::finish(const RunStats&) {
  if (static_cast<std::int64_t>(kept_.size()) != shots_)
    throw run_error(
        out_dir_.string(),
        "ICESat-2 granules: " + std::to_string(shots_ - kept_.size()) + " records never written");
  std::vector<BeamTrack> beams;
  for (const GranuleBeam& granule_beam : settings_.beams)
    beams.push_back(gather_beam(granule_beam));
  const Atl08Settings atl08;
  const std::vector<Atl08Classes> classes = classify_beams(beams, atl08);
  if (settings_.atl03) write_atl03(out_dir_ / "atl03.h5", beams, classes, info_);
  if (settings_.atl08) write_atl08(out_dir_ / "atl08.h5", beams, classes, atl08, info_);
  done_ = true;
}

void Icesat2Writer::abort() noexcept {
  done_ = true;
  kept_.clear();
}

namespace {

const Registration<ProductWriter> icesat2_writer(
    "atl03.h5 atl08.h5", 50, [](const WriterContext& c) -> std::unique_ptr<ProductWriter> {
      if (!c.icesat2.atl03 && !c.icesat2.atl08) return nullptr;
      return std::make_unique<Icesat2Writer>(c.out_dir, c.icesat2, c.info);
    });

}  // namespace

}  // namespace glaswave
