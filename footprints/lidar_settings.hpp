// The lidar that makes the footprints (the seed's Table 2) and its detector, as the configuration
// declares them and the transport and the receivers use them: pipeline/config/keys.cpp declares
// each key beside the member below that it sets, and the shot reads the same struct, so no
// setting is copied from one struct into another. The defaults are the `north2010` preset's.
#pragma once

#include <cmath>
#include <optional>
#include <string>
#include <vector>

namespace glaswave {

// One band of the laser.
struct LidarBand {
  double wavelength_nm = 0.0;
  double pulse_energy_mJ = 0.0;
  double atmos_transmission_roundtrip = 1.0;
  std::string name;  // the key of per-band values in the configuration and the products
};

// The lidar's beam, field of view, pulse and digitiser window, and its bands.
struct LidarSettings {
  double pulse_sigma_ns = 5.0;
  double divergence_sigma_rad = 0.00011;  // beam angular RMS width per axis
  // "gaussian" (intensity ∝ exp(-θ²/2σ²)) or "uniform": a top-hat cone of half-angle
  // 2 divergence_sigma_rad, the same RMS per axis and the Gaussian's 1/e² edge (RAMI-IV's lidar
  // lights a disc uniformly).
  std::string beam_profile = "gaussian";
  double ifov_rad = 0.0004;  // detector full field of view (top-hat cone)
  double telescope_area_m2 = 0.709;
  double bin_ns = 1.0;
  int bins = 544;
  std::vector<LidarBand> bands;
};

// The pulse kernel's half-width in bins (6 sigma): the transport's tallies reach this far beyond
// the window on each side, and the memory estimate counts those bins.
inline int pulse_margin_bins(const LidarSettings& lidar) {
  return static_cast<int>(std::ceil(6.0 * lidar.pulse_sigma_ns / lidar.bin_ns));
}

// A photon-counting receiver's detector (ATLAS's strong beam by default: docs/icesat2.md): the
// sensor's keys (`photon_efficiency`, `filter_bandwidth_nm`, `dead_time_ns`) and the
// photon-counting receiver's settings are both this struct, so that each default is written once.
struct PhotonDetectorSettings {
  double photon_efficiency = 0.45 * 0.15;  // optical throughput times photon detection efficiency
  double filter_bandwidth_nm = 0.038;      // the receiver filter's equivalent (rectangular) width
  double dead_time_ns = 3.2;               // each detector channel's, non-paralysable
};

// The detector and digitiser between the received light and the recorded waveform
// (`"detector"`). Off by default: the waveform is then the noise-free received power. Every level
// is in W of received light at the detector's input except saturation_W, the digitiser's full
// scale after the gain, so rx_waveform keeps its unit whatever the gain.
struct DetectorSettings {
  bool enabled = false;             // whether the receiver applies the detector at all
  double background_W = 0.0;        // mean background light in the field of view (sunlit scene)
  bool photon_noise = false;        // Poisson statistics of signal and background photons
  double quantum_efficiency = 1.0;  // photoelectrons per photon, for photon_noise
  double noise_rms_W = 0.0;         // Gaussian detector (dark and amplifier) noise, RMS
  double gain = 1.0;                // amplification before the digitiser
  int bits = 0;                     // digitiser resolution; 0: not digitised
  // Full scale at the digitiser (its input-referred level is saturation_W / gain): output above
  // it clips. Required when bits > 0; absent: no saturation.
  std::optional<double> saturation_W;
};

}  // namespace glaswave
