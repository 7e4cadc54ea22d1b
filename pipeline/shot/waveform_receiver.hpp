// The first receiver: the analog detector and digitiser (pipeline/transport/detector.hpp) turn
// the received power into the recorded waveform, which the waveform processing
// (pipeline/products/waveform_metrics.hpp) decomposes into Gaussians and measures; the seed's
// eq. (1) gives each band's reflectance. Registered as "waveform".
#pragma once

#include <optional>

#include "pipeline/shot/receiver.hpp"

namespace glaswave {

class WaveformReceiver : public Receiver {
 public:
  explicit WaveformReceiver(const ReceiverSettings& settings);

  void receive(ShotReturns returns, ShotRecord& record) const override;

 private:
  void receive_energies(const ShotReturns& returns, ShotRecord& record) const;
  void record_waveforms(ShotRecord& record, ShotWaveforms waveforms,
                        std::int64_t shot_number) const;
  std::vector<double> surface_reflectance(const ShotRecord& record, double range_m) const;

  ReceiverSettings settings_;
  std::optional<Detector> detector_;
};

}  // namespace glaswave
