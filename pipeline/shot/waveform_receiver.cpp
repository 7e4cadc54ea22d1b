// The analog detector and the waveform processing of a shot's returns.
#include "pipeline/shot/waveform_receiver.hpp"

#include <algorithm>
#include <numbers>

#include "pipeline/products/product_fields.hpp"
#include "pipeline/products/waveform_metrics.hpp"

namespace glaswave {

WaveformReceiver::WaveformReceiver(const ReceiverSettings& settings) : settings_(settings) {
  if (settings_.detector) detector_.emplace(*settings_.detector, settings_.seed);
}

void WaveformReceiver::receive(ShotReturns returns, ShotRecord& record) const {
  if (returns.waveforms.total_W.empty()) {
    receive_energies(returns, record);
    return;
  }
  // The Monte Carlo variance weighs the decomposition's tests; it is not a product.
  const std::vector<std::vector<double>> mc_variance_W2 =
      std::move(returns.waveforms.total_variance_W2);
  record_waveforms(record, std::move(returns.waveforms), returns.shot_number);
  // Noise-free waveforms get the fraction-of-peak threshold, detected ones the threshold above
  // their noise.
  WaveformProcessing processing;
  processing.pulse_sigma_ns = settings_.lidar.pulse_sigma_ns;
  processing.noise_free = !detector_.has_value();
  if (settings_.metrics && settings_.metrics_read) {
    process_shot_waveforms(record, settings_.lidar.bin_ns, processing, mc_variance_W2);
  } else if (settings_.metrics) {  // unread: the flags alone, the metrics fill
    flag_shot_signal(record, settings_.lidar.bin_ns, processing);
  } else {  // as a flagged shot's: fill
    fill_fields(record, FieldSource::metrics, ProductShape{.bands = settings_.lidar.bands.size()});
  }
  record.reflectance = surface_reflectance(record, returns.range_m);
}

// Without power waveforms (a receiver whose returns form has none: nothing reads them) the
// record keeps the energies alone, the metrics fill; a shot with no energy in any band is
// flagged no signal, as the processing of its all-zero noise-free waveform would flag it.
void WaveformReceiver::receive_energies(const ShotReturns& returns, ShotRecord& record) const {
  const ShotWaveforms& w = returns.waveforms;
  record.rx_energy_J = w.energy_J;
  record.rx_energy_canopy_J = w.canopy_energy_J;
  record.rx_energy_ground_J = w.ground_energy_J;
  fill_fields(record, FieldSource::metrics, ProductShape{.bands = w.energy_J.size()});
  const bool signal =
      std::any_of(w.energy_J.begin(), w.energy_J.end(), [](double e) { return e > 0.0; });
  if (record.quality_flag == quality_good && !w.energy_J.empty() && !signal) {
    record.quality_flag = quality_invalid;
    record.quality_reason = reason_no_signal;
  }
  record.reflectance = surface_reflectance(record, returns.range_m);
}

void WaveformReceiver::record_waveforms(ShotRecord& record, ShotWaveforms waveforms,
                                        std::int64_t shot_number) const {
  record.rx_waveform_W = std::move(waveforms.total_W);
  record.rx_waveform_canopy_W = std::move(waveforms.canopy_W);
  record.rx_waveform_ground_W = std::move(waveforms.ground_W);
  record.rx_waveform_order_W = std::move(waveforms.order_W);
  record.rx_energy_J = waveforms.energy_J;
  record.rx_energy_canopy_J = waveforms.canopy_energy_J;
  record.rx_energy_ground_J = waveforms.ground_energy_J;
  if (!detector_) return;
  // The detector turns the received power into the recorded waveform (its canopy and ground
  // parts stay the noise-free truth); rx_energy stays the integral of rx_waveform.
  const double bin_ns = settings_.lidar.bin_ns, bin_s = bin_ns * 1e-9;
  for (std::size_t band = 0; band < settings_.lidar.bands.size(); ++band) {
    record.rx_waveform_W[band] =
        detector_->record(record.rx_waveform_W[band], bin_ns,
                          settings_.lidar.bands[band].wavelength_nm, shot_number, band);
    double sum_W = 0.0;
    for (double p : record.rx_waveform_W[band]) sum_W += p;
    record.rx_energy_J[band] = sum_W * bin_s;
  }
}

std::vector<double> WaveformReceiver::surface_reflectance(const ShotRecord& record,
                                                          double range_m) const {
  // The seed's eq. (1): rho = pi E_rec R^2 / (E_t A_T T). E_rec is all of the received energy;
  // from a detected waveform it is what a user would take: the energy above the noise between
  // signal begin and end (energy_tr), as background and noise summed over the whole window
  // would swamp it.
  std::vector<double> reflectance;
  for (std::size_t band = 0; band < settings_.lidar.bands.size(); ++band) {
    const LidarBand& b = settings_.lidar.bands[band];
    const double received_J = detector_ ? record.energy_tr_J[band] : record.rx_energy_J[band];
    reflectance.push_back(std::numbers::pi * received_J * range_m * range_m /
                          (b.pulse_energy_mJ * 1e-3 * settings_.lidar.telescope_area_m2 *
                           b.atmos_transmission_roundtrip));
  }
  return reflectance;
}

namespace {
const ReceiverRegistration waveform(
    "waveform", 0, {"the received waveform and its processing", {.waveform = true}},
    [](const ReceiverSettings& s) { return std::make_unique<WaveformReceiver>(s); });
}  // namespace

}  // namespace glaswave
