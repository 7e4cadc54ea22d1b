// The photon-counting receiver (ICESat-2's ATLAS), the Receiver interface's second
// implementation, registered as "photon_counting": the energy the transport scored in each bin
// before the pulse becomes photon events, each spread by the pulse
// (pipeline/transport/photon_counting.hpp), with the sun's background at the shot's time and
// place and the detector's dead time; each event is geolocated on the beam's axis and carries
// its truth. The record keeps the waveform receiver's fields too (the expected return, or its
// energies alone when nothing reads the waveforms).
#pragma once

#include <optional>

#include "pipeline/shot/receiver.hpp"
#include "pipeline/shot/waveform_receiver.hpp"

namespace glaswave {

// The most background photons a second a shot of beam `p` can be given: its fixed rate, none,
// or the sun's worst case, overhead over a white scene through the band's atmosphere (its layers
// when there are: their SkyLight, traced here). check_run
// bounds a shot's background photons by it, before any shot.
double most_background_rate_Hz(const ReceiverSettings& settings, const PhotonCountingSettings& p);

// The photons the detector counts per joule of received light at `wavelength_nm`: its
// efficiency over a photon's energy, as the receiver turns each bin's energy into photons (what
// rt on ATL03 scales its table's watts by, the beam's share of the pulse aside).
double detected_photons_per_J(const PhotonDetectorSettings& detector, double wavelength_nm);

class PhotonCountingReceiver : public Receiver {
 public:
  explicit PhotonCountingReceiver(const ReceiverSettings& settings);

  // Band 0's returns as the transport scored them, before the pulse: the expected photons of
  // the top of the canopy (its bins up to the one by which a tenth of the canopy's energy has
  // arrived), the rest of the canopy and the ground, each split by scattering order in
  // proportion to the bin's per-order energy; the background's rate from the sun
  // (SolarBackground) over a Lambertian scene of the shot's eq. (1) reflectance (through the
  // layers: their SkyLight, traced once when the receiver is made), or the
  // settings' fixed rate, or none; the events drawn by (seed, shot, beam, bin), each spread by
  // the pulse, the dead time applied. The record's waveform fields are the waveform receiver's.
  void receive(ShotReturns returns, ShotRecord& record) const override;
  bool photon_events() const override { return true; }
  // The power only when the record's waveform fields are read (settings.metrics_read).
  ReturnsForm returns_form() const override { return {settings_.metrics_read, true}; }

 private:
  // The settings of the beam that fired the shot.
  const PhotonCountingSettings& beam_settings(int beam) const;
  double background_rate_Hz(const PhotonCountingSettings& p, const ShotRecord& record,
                            double received_J, double range_m) const;

  ReceiverSettings settings_;
  WaveformReceiver waveform_;
  LidarModel lidar_;
  std::optional<SkyLight> sky_;  // with the layers and a sun background
};

}  // namespace glaswave
