// The detector model: what a real receiver makes of the simulated received power, so that a
// waveform can look like GLAS's (background light, photon statistics, detector noise, gain,
// saturation and a digitiser of a few bits). Its noise is counter-based, keyed by
// (seed, shot, band, bin) as the transport's rays are keyed by (seed, shot, ray): a shot's
// recorded waveform is the same bits for any thread count and any split of the track.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

namespace glaswave {

class Detector {
 public:
  // The signal chain, every level in W of received light at the detector's input except
  // saturation_W, the digitiser's full scale after the gain. The engine fills it from the
  // configuration's detector.
  struct Settings {
    double background_W = 0.0;           // mean background light in the field of view
    bool photon_noise = false;           // Poisson statistics of signal and background photons
    double quantum_efficiency = 1.0;     // photoelectrons per photon, for photon_noise
    double noise_rms_W = 0.0;            // Gaussian detector (dark and amplifier) noise, RMS
    double gain = 1.0;                   // amplification before the digitiser
    int bits = 0;                        // digitiser resolution; 0: not digitised
    std::optional<double> saturation_W;  // full scale; absent: no saturation
  };

  Detector(const Settings& settings, std::uint64_t seed);

  const Settings& settings() const { return settings_; }

  // The recorded waveform for the received power of one band (W per bin of `bin_ns`), in W
  // referred to the detector's input. In order, for each bin:
  //   x = power + background_W
  //   photon_noise: x = hv/dt * Poisson(QE x dt / hv) / QE   (hv from wavelength_nm)
  //   x += noise_rms_W * N(0, 1)
  //   v = gain x, clipped to saturation_W; with bits, rounded to the nearest of 2^bits levels
  //       0, lsb, ..., saturation_W (lsb = saturation_W / (2^bits - 1)), below 0 reading 0
  //   recorded = v / gain
  // Throws std::invalid_argument for a band >= 2^8 or more than 2^24 bins (the keys' room).
  std::vector<double> record(std::span<const double> power_W, double bin_ns, double wavelength_nm,
                             std::int64_t shot, std::size_t band) const;

 private:
  Settings settings_;
  std::uint64_t seed_;
};

}  // namespace glaswave
