// What a kind of receiver is (`sensor.receiver`), as the configuration's rules and the engine ask
// it instead of naming it: each receiver declares these beside its registration
// (Registry<PartKind<ReceiverTraits>>, core/part_kind.hpp; pipeline/shot/receiver.hpp), on a floor
// that the configuration and the receivers both see.
#pragma once

namespace glaswave {

struct ReceiverTraits {
  // Its records hold the received waveform and its processing: RAMI's lidar measurements and the
  // forward table (`glaswave table`) are made of it.
  bool waveform = false;
  bool every_order =
      false;  // it takes the returns of every scattering order (photons carry theirs)
  bool shares_scenes = false;  // its footprints overlap (10 kHz): shots share their stretch's scene
  // It flies ATLAS's beams (sensor.beams, sc_orient): a pass's beams fly their own ground tracks,
  // each received with its own photon-counting settings, and the ICESat-2 granules (atl03.h5,
  // atl08.h5) are its own.
  bool atlas_beams = false;
};

}  // namespace glaswave
