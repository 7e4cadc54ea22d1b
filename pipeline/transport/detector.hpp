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

#include "footprints/lidar_settings.hpp"

namespace glaswave {

class Detector {
 public:
  // The signal chain, the configuration's `"detector"` as it reads it.
  using Settings = DetectorSettings;

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
