// The photon-counting receiver: expected photons by class and order, the sun's background, keyed
// draws, dead time, and each event geolocated on the beam's axis.
#include "pipeline/shot/photon_receiver.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "footprints/sun_position.hpp"
#include "pipeline/transport/photon_counting.hpp"

namespace glaswave {
namespace {

// The bins [begin, end) that hold the shot's signal: outside them neither the canopy's nor the
// ground's power is above 0, so no expected photon is either (all of them are 0 there).
struct SignalBins {
  std::size_t begin = 0, end = 0;
};

SignalBins signal_bins(const std::vector<double>& canopy_W, const std::vector<double>& ground_W) {
  SignalBins span{canopy_W.size(), 0};
  for (std::size_t bin = 0; bin < canopy_W.size(); ++bin)
    if (!(canopy_W[bin] <= 0.0) || !(ground_W[bin] <= 0.0)) {  // NaN counts as signal
      span.begin = std::min(span.begin, bin);
      span.end = bin + 1;
    }
  if (span.end == 0) span.begin = 0;
  return span;
}

// The sources of one truth class: its expected photons, split by scattering order in proportion
// to the bin's per-order power when there is one (0 outside the signal's bins).
void add_sources(std::vector<std::vector<double>>& means, std::vector<PhotonSource>& sources,
                 const std::vector<double>& photons, PhotonTruth truth,
                 const std::vector<std::vector<double>>& order_W,
                 const std::vector<double>& total_W, SignalBins signal) {
  if (order_W.empty()) {
    means.push_back(photons);
    sources.push_back({{}, truth, 1});
    return;
  }
  for (std::size_t order = 0; order < order_W.size(); ++order) {
    std::vector<double> part(photons.size(), 0.0);
    for (std::size_t bin = signal.begin; bin < signal.end; ++bin)
      if (total_W[bin] > 0.0)
        part[bin] = photons[bin] * std::clamp(order_W[order][bin] / total_W[bin], 0.0, 1.0);
    means.push_back(std::move(part));
    sources.push_back({{}, truth, static_cast<std::uint8_t>(order + 1)});
  }
}

// The time (bins' clock) by which a tenth of the canopy's expected photons has arrived (all of
// them in the signal's bins).
double canopy_top_ns(const std::vector<double>& canopy, const std::vector<double>& times_ns,
                     SignalBins signal) {
  double total = 0.0;
  for (std::size_t bin = signal.begin; bin < signal.end; ++bin) total += canopy[bin];
  double sum = 0.0;
  for (std::size_t bin = signal.begin; bin < signal.end; ++bin) {
    sum += canopy[bin];
    if (sum >= 0.1 * total && total > 0.0) return times_ns[bin];
  }
  return -std::numeric_limits<double>::infinity();
}

}  // namespace

PhotonCountingReceiver::PhotonCountingReceiver(const ReceiverSettings& settings)
    : settings_(settings), waveform_(settings), lidar_(settings.lidar) {
  if (settings_.photons.empty()) settings_.photons.emplace_back();
}

const PhotonCountingSettings& PhotonCountingReceiver::beam_settings(int beam) const {
  for (const PhotonCountingSettings& p : settings_.photons)
    if (static_cast<std::int64_t>(p.beam) == beam) return p;
  return settings_.photons.front();
}

double PhotonCountingReceiver::background_rate_Hz(const PhotonCountingSettings& p,
                                                  const ShotRecord& record,
                                                  const ShotWaveforms& waveforms,
                                                  double range_m) const {
  if (p.background == BackgroundSource::none) return 0.0;
  if (p.background == BackgroundSource::rate) return p.background_rate_Hz;
  const LidarBand& band = settings_.lidar.bands[0];
  // The scene's reflectance from the shot's own return, the seed's eq. (1).
  const double energy_J = waveforms.energy_J[0];
  const double reflectance =
      std::numbers::pi * energy_J * range_m * range_m /
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
  b.efficiency = p.efficiency;
  b.wavelength_nm = band.wavelength_nm;
  return glaswave::background_rate_Hz(b);
}

void PhotonCountingReceiver::receive(ShotReturns returns, ShotRecord& record) const {
  const PhotonCountingSettings& p = beam_settings(returns.beam);
  // The returns are the power of the band's pulse energy; a weak beam carries a part of it.
  scale_pulse_energy(returns.waveforms, p.energy_ratio);
  const ShotWaveforms& w = returns.waveforms;
  const double bin_ns = settings_.lidar.bin_ns;
  const double wavelength_nm = settings_.lidar.bands[0].wavelength_nm;
  const double efficiency = p.efficiency;
  const std::vector<double> canopy =
      expected_photons(w.canopy_W[0], bin_ns, wavelength_nm, efficiency);
  const std::vector<double> ground =
      expected_photons(w.ground_W[0], bin_ns, wavelength_nm, efficiency);
  const std::vector<std::vector<double>> no_orders;
  const auto& orders = w.order_W.empty() ? no_orders : w.order_W[0];
  const SignalBins signal = signal_bins(w.canopy_W[0], w.ground_W[0]);
  std::vector<std::vector<double>> means;
  std::vector<PhotonSource> sources;
  add_sources(means, sources, canopy, PhotonTruth::canopy, orders, w.total_W[0], signal);
  add_sources(means, sources, ground, PhotonTruth::ground, orders, w.total_W[0], signal);
  for (std::size_t k = 0; k < sources.size(); ++k) sources[k].mean_per_bin = means[k];

  const std::vector<double> times_ns = lidar_.bin_time_ns();
  PhotonDraw draw{settings_.seed, returns.shot_number,
                  p.beam,         bin_ns,
                  canopy.size(),  background_rate_Hz(p, record, w, returns.range_m),
                  p.channels};
  draw.signal_begin = signal.begin;
  draw.signal_end = signal.end;
  const std::vector<PhotonEvent> events =
      apply_dead_time(draw_photons(draw, sources), p.dead_time_ns);
  const double top_ns = canopy_top_ns(canopy, times_ns, signal);
  const double window_start_ns = times_ns.front() - 0.5 * bin_ns;
  const std::function<Geodetic(double)> position_at = returns.position_at;
  waveform_.receive(std::move(returns), record);
  // Eq. (1)'s reflectance divides by the band's pulse energy, not the beam's.
  if (p.energy_ratio != 1.0)
    for (double& r : record.reflectance) r /= p.energy_ratio;
  if (!p.keep_orders) record.rx_waveform_order_W.clear();
  for (const PhotonEvent& e : events) {
    const double time_ns = window_start_ns + e.time_ns;
    const Geodetic at = position_at(time_ns);
    PhotonTruth truth = e.truth_class;
    if (truth == PhotonTruth::canopy && time_ns <= top_ns) truth = PhotonTruth::top_of_canopy;
    record.photon_time_ns.push_back(time_ns);
    record.photon_lat_deg.push_back(at.lat_deg);
    record.photon_lon_deg.push_back(at.lon_deg);
    record.photon_h_m.push_back(at.h_m);
    record.photon_class.push_back(static_cast<std::int32_t>(truth));
    record.photon_order.push_back(e.order);
  }
}

}  // namespace glaswave
