// The photon-counting receiver: expected photons by class and order, the sun's background, keyed
// draws, dead time, and each event geolocated on the beam's axis.
#include "pipeline/shot/photon_receiver.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "footprints/sun_position.hpp"
#include "pipeline/transport/photon_counting.hpp"
#include "pipeline/transport/sky_light.hpp"

namespace glaswave {
namespace {

// The expected photons of a shot's truth classes and scattering orders in its scored bins:
// top of canopy (the canopy's bins up to the one by which a tenth of its expected photons has
// arrived), the rest of the canopy, the ground; each split by order in proportion to the bin's
// per-order energy when the transport keeps orders (it keeps them for this receiver).
struct ShotSources {
  std::vector<std::vector<double>> means;
  std::vector<PhotonSource> sources;
};

ShotSources shot_sources(const ScoredReturns& scored, double wavelength_nm, double efficiency) {
  const std::size_t bins = scored.size();
  const std::vector<double> canopy =
      expected_photons(scored.canopy_J[0], wavelength_nm, efficiency);
  const std::vector<double> ground =
      expected_photons(scored.ground_J[0], wavelength_nm, efficiency);
  // The canopy's top: its bins (in time order) up to the one by which a tenth of its photons has
  // arrived.
  double canopy_photons = 0.0;
  for (const double n : canopy) canopy_photons += n;
  std::size_t top_end = 0;  // the top's bins are [0, top_end)
  for (double sum = 0.0; top_end < bins && canopy_photons > 0.0;) {
    sum += canopy[top_end++];
    if (sum >= 0.1 * canopy_photons) break;
  }
  const std::vector<std::vector<double>> whole{scored.total_J[0]};
  const std::vector<std::vector<double>>& orders =
      scored.order_J.empty() ? whole : scored.order_J[0];
  ShotSources shot;
  auto add = [&](const std::vector<double>& photons, PhotonTruth truth, std::size_t from,
                 std::size_t to) {
    for (std::size_t order = 0; order < orders.size(); ++order) {
      std::vector<double>& mean = shot.means.emplace_back(bins, 0.0);
      for (std::size_t bin = from; bin < to; ++bin) {
        const double total_J = scored.total_J[0][bin];
        if (total_J > 0.0)
          mean[bin] = photons[bin] * std::clamp(orders[order][bin] / total_J, 0.0, 1.0);
      }
      shot.sources.push_back({{}, truth, static_cast<std::uint8_t>(order + 1)});
    }
  };
  add(canopy, PhotonTruth::top_of_canopy, 0, top_end);
  add(canopy, PhotonTruth::canopy, top_end, bins);
  add(ground, PhotonTruth::ground, 0, bins);
  for (std::size_t k = 0; k < shot.sources.size(); ++k)
    shot.sources[k].mean_per_bin = shot.means[k];
  return shot;
}

}  // namespace

PhotonCountingReceiver::PhotonCountingReceiver(const ReceiverSettings& settings)
    : settings_(settings), waveform_(settings), lidar_(settings.lidar) {
  if (settings_.photons.empty()) settings_.photons.emplace_back();
  const bool sun = std::any_of(
      settings_.photons.begin(), settings_.photons.end(),
      [](const PhotonCountingSettings& p) { return p.background == BackgroundSource::sun; });
  if (settings_.atmosphere && sun)
    sky_ = sky_light(*settings_.atmosphere, settings_.lidar.bands.size(), 0, settings_.seed);
}

const PhotonCountingSettings& PhotonCountingReceiver::beam_settings(int beam) const {
  for (const PhotonCountingSettings& p : settings_.photons)
    if (static_cast<std::int64_t>(p.beam) == beam) return p;
  return settings_.photons.front();
}

double detected_photons_per_J(const PhotonDetectorSettings& detector, double wavelength_nm) {
  return photons_per_J(detector.photon_efficiency, wavelength_nm);
}

double most_background_rate_Hz(const ReceiverSettings& settings, const PhotonCountingSettings& p) {
  if (p.background == BackgroundSource::none) return 0.0;
  if (p.background == BackgroundSource::rate) return p.background_rate_Hz;
  const LidarBand& band = settings.lidar.bands.at(0);
  SolarBackground b;
  b.sun_zenith_deg = 0.0;
  b.reflectance = 1.0;
  b.transmission_one_way = std::sqrt(band.atmos_transmission_roundtrip);
  b.filter_bandwidth_nm = p.filter_bandwidth_nm;
  b.ifov_rad = settings.lidar.ifov_rad;
  b.telescope_area_m2 = settings.lidar.telescope_area_m2;
  b.efficiency = p.photon_efficiency;
  b.wavelength_nm = band.wavelength_nm;
  std::optional<SkyLight> sky;
  if (settings.atmosphere) {
    sky = sky_light(*settings.atmosphere, settings.lidar.bands.size(), 0, settings.seed);
    b.sky = &*sky;
  }
  return glaswave::background_rate_Hz(b);
}

double PhotonCountingReceiver::background_rate_Hz(const PhotonCountingSettings& p,
                                                  const ShotRecord& record, double received_J,
                                                  double range_m) const {
  if (p.background == BackgroundSource::none) return 0.0;
  if (p.background == BackgroundSource::rate) return p.background_rate_Hz;
  const LidarBand& band = settings_.lidar.bands[0];
  // The scene's reflectance from the shot's own return, the seed's eq. (1).
  const double reflectance =
      std::numbers::pi * received_J * range_m * range_m /
      (band.pulse_energy_mJ * 1e-3 * p.energy_ratio * settings_.lidar.telescope_area_m2 *
       band.atmos_transmission_roundtrip);
  const SunPosition sun = sun_position(record.time_s, record.lat_deg, record.lon_deg);
  SolarBackground b;
  b.sun_zenith_deg = 90.0 - sun.elevation_deg;
  b.reflectance = std::clamp(reflectance, 0.0, 1.0);
  b.transmission_one_way = std::sqrt(band.atmos_transmission_roundtrip);
  b.filter_bandwidth_nm = p.filter_bandwidth_nm;
  b.ifov_rad = settings_.lidar.ifov_rad;
  b.telescope_area_m2 = settings_.lidar.telescope_area_m2;
  b.efficiency = p.photon_efficiency;
  b.wavelength_nm = band.wavelength_nm;
  if (sky_) b.sky = &*sky_;
  return glaswave::background_rate_Hz(b);
}

void PhotonCountingReceiver::receive(ShotReturns returns, ShotRecord& record) const {
  const PhotonCountingSettings& p = beam_settings(returns.beam);
  // The returns are the power of the band's pulse energy; a weak beam carries a part of it.
  scale_pulse_energy(returns.waveforms, p.energy_ratio);
  const ScoredReturns& scored = returns.waveforms.scored;
  const LidarSettings& lidar = settings_.lidar;
  const ShotSources shot = shot_sources(scored, lidar.bands[0].wavelength_nm, p.photon_efficiency);
  double received_J = 0.0;
  for (const double e : scored.total_J[0]) received_J += e;
  PhotonDraw draw{settings_.seed,
                  returns.shot_number,
                  p.beam,
                  lidar.bin_ns,
                  static_cast<std::size_t>(lidar.bins),
                  background_rate_Hz(p, record, received_J, returns.range_m),
                  p.channels};
  // The scored bins are the tally's, which begins its pulse margin before the window.
  draw.signal_bins = scored.bins;
  draw.grid_offset_bins = -lidar_.margin_bins();
  draw.pulse_sigma_ns = lidar.pulse_sigma_ns;
  const std::vector<PhotonEvent> events =
      apply_dead_time(draw_photons(draw, shot.sources), p.dead_time_ns);
  const double window_start_ns = lidar_.bin_time_ns(0) - 0.5 * lidar.bin_ns;
  const std::function<Geodetic(double)> position_at = returns.position_at;
  waveform_.receive(std::move(returns), record);
  // Eq. (1)'s reflectance divides by the band's pulse energy, not the beam's.
  if (p.energy_ratio != 1.0)
    for (double& r : record.reflectance) r /= p.energy_ratio;
  if (!p.keep_orders) record.rx_waveform_order_W.clear();
  for (const PhotonEvent& e : events) {
    const double time_ns = window_start_ns + e.time_ns;
    const Geodetic at = position_at(time_ns);
    record.photon_time_ns.push_back(time_ns);
    record.photon_lat_deg.push_back(at.lat_deg);
    record.photon_lon_deg.push_back(at.lon_deg);
    record.photon_h_m.push_back(at.h_m);
    record.photon_class.push_back(static_cast<std::int32_t>(e.truth_class));
    record.photon_order.push_back(e.order);
  }
}

namespace {
const ReceiverRegistration photon_counting(
    "photon_counting", 1,
    {"ICESat-2's photon events, written to `atl03.h5` and `atl08.h5`; docs/icesat2.md",
     {.every_order = true, .shares_scenes = true, .atlas_beams = true}},
    [](const ReceiverSettings& s) { return std::make_unique<PhotonCountingReceiver>(s); });
}  // namespace

}  // namespace glaswave
