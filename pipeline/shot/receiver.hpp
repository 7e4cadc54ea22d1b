// What the receiver makes of a shot: a Receiver turns the shot's binned returns (the received
// power per band and time bin, as the transport tallies it) into what the record carries.
//
// The first receiver is the analog one (waveform_receiver.hpp): detector and digitiser, then
// the waveform processing (Gaussian decomposition, metrics, eq. (1)'s reflectance). A photon-
// counting receiver (ICESat-2's ATLAS) is the second: it draws photon events from the returns
// and writes them to the record's variable-length fields (ShotRecord::photon_*, stored in
// shots.nc as CF contiguous ragged arrays along the `photon` dimension).
//
// A new receiver is one class and one registration in its own .cpp (ReceiverRegistration below,
// keyed by ReceiverSettings::kind): the configuration, the engine and the transport do not change.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/part_kind.hpp"
#include "core/registry.hpp"
#include "footprints/atmosphere_settings.hpp"
#include "footprints/receiver_traits.hpp"
#include "pipeline/products/shot_record.hpp"
#include "pipeline/transport/detector.hpp"
#include "pipeline/transport/lidar_model.hpp"
#include "pipeline/transport/photon_counting.hpp"
#include "pipeline/transport/shot_transport.hpp"
#include "terrain/local_frame.hpp"

namespace glaswave {

// One shot's returns, as the receiver sees them.
struct ShotReturns {
  // [band][bin] received power (W) in the lidar's bins (LidarModel::bin_time_ns: two-way time
  // after the return from range_m), its canopy and ground parts (the truth of each bin's
  // light), per order when asked for, and the Monte Carlo variance of the total.
  ShotWaveforms waveforms;
  std::int64_t shot_number = 0;
  int beam = -1;         // the footprint's beam (Footprint::beam): ATLAS's spot number, or -1
  double range_m = 0.0;  // to the footprint centre
  // Where light of two-way time `time_ns` (the bins' clock) was scattered, on the beam's axis:
  // latitude, longitude and height above the ellipsoid.
  std::function<Geodetic(double time_ns)> position_at;
};

// The returns of a pulse of `scale` times the sensor's energy (a GEDI coverage beam's half, an
// ATLAS weak beam's 45/175): every received power and energy scales with it, the Monte Carlo
// variance with its square.
void scale_pulse_energy(ShotWaveforms& waveforms, double scale);

struct ReceiverKind;

class Receiver {
 public:
  // What a registration holds (core/registry.hpp): how to make one, and what the run around it
  // must know before it is made.
  using Factory = ReceiverKind;

  virtual ~Receiver() = default;

  // Fills the record's receiver fields from the returns (the record already holds the shot's
  // geolocation). Thread-safe: every thread of a run calls it at once. The result may depend
  // only on the returns and the shot number (counter-based noise), never on the thread.
  virtual void receive(ShotReturns returns, ShotRecord& record) const = 0;

  // Whether records carry photon events: the products then hold the `photon` dimension and
  // the ragged photon_* fields, which are left out otherwise.
  virtual bool photon_events() const { return false; }

  // The form of the returns it takes (ShotReturns::waveforms): the power in the window's bins,
  // pulse-shaped, and the energies scored before the pulse (ShotWaveforms::scored), from which a
  // photon-counting receiver draws. Without power the waveforms and their integrals' fields are
  // the scored energies' sums alone.
  struct ReturnsForm {
    bool power = true;
    bool scored = false;
  };
  virtual ReturnsForm returns_form() const { return {}; }
};

// What a receiver is made from.
struct ReceiverSettings {
  std::string kind = "waveform";               // the registered receiver's name
  LidarSettings lidar;                         // bands, bins, pulse, telescope
  std::optional<Detector::Settings> detector;  // none: the noise-free received power
  bool metrics = true;                         // the waveform processing (decomposition, metrics)
  // Whether anything reads the metrics: false (a photon-counting run that writes its ICESat-2
  // granules alone, made from the photons and the truth) skips the decomposition and leaves
  // them fill, the shots flagged no or low signal as the processing would flag them.
  bool metrics_read = true;
  std::uint64_t seed = 1;  // the detector's noise is keyed by (seed, shot, band, bin)
  // "photon_counting": one per beam of the run, each keyed by its `beam` (ATLAS's spot number);
  // a shot is received as the beam whose key is its footprint's beam, the first when none is.
  // Empty: ATLAS's strong beam.
  std::vector<PhotonCountingSettings> photons;
  // The atmosphere's layers: photon counting's sun background comes through them (SkyLight, at
  // the first band); none: through the bands' transmission, as before.
  std::optional<AtmosphereSettings> atmosphere;
};

using ReceiverFactory = std::function<std::unique_ptr<Receiver>(const ReceiverSettings&)>;

// One kind of receiver: how to make one. What the configuration and the engine must know of the
// kind before one is made (its ReceiverTraits, footprints/lidar_settings.hpp) it declares beside
// it.
struct ReceiverKind {
  ReceiverFactory make;
};

// One kind's registration, from its own .cpp: its declaration (Registry<PartKind<ReceiverTraits>>,
// core/part_kind.hpp: the configuration's allowed names, the table of keys' description, the
// traits that the configuration's rules and the engine ask) and its factory (Registry<Receiver>),
// under one name (waveform_receiver.cpp, photon_receiver.cpp; the shot library is linked whole):
//   const ReceiverRegistration waveform("waveform", 0, {"the received waveform ...",
//                                       {.waveform = true}}, [](const ReceiverSettings& s) {...});
struct ReceiverRegistration {
  ReceiverRegistration(const std::string& name, int order,
                       PartKind<ReceiverTraits>::Declaration declaration, ReceiverFactory make)
      : declared(name, order, std::move(declaration)), made(name, order, {std::move(make)}) {}
  Registration<PartKind<ReceiverTraits>> declared;
  Registration<Receiver> made;
};

// The receiver of `settings.kind`. Throws a setting error at `kind` for an unknown name.
std::unique_ptr<Receiver> make_receiver(const ReceiverSettings& settings);

// What the receiver kind `kind` declared of itself. Throws a setting error at `kind` for a name
// that declared nothing.
ReceiverTraits receiver_traits(const std::string& kind);

}  // namespace glaswave
