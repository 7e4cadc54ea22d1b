// What a simulated shot hands to the product writers: geolocation, waveforms per band, and
// the metrics derived from them. Arrays are [band][bin], bins in time order (bin 0 nearest
// the spacecraft).
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "core/glas_time.hpp"

namespace glaswave {

// A band as the products name it.
struct ProductBand {
  std::string name;
  double wavelength_nm = 0.0;
  double atmos_transmission_roundtrip = 1.0;  // what GLAS's uncorrected reflectivity keeps
};

// ShotRecord::beam of a shot that no GEDI beam fired (a synthetic or a GLAH14 track).
inline constexpr std::uint8_t kNoBeam = 255;

// quality_flag values (flag_values / flag_meanings in shots.nc): GEDI L2A's convention, 1 for a
// valid waveform, so that `quality_flag == 1` keeps the good shots.
enum QualityFlag : std::uint8_t {
  quality_invalid = 0,  // no waveform: quality_reason says why
  quality_good = 1,
};

// quality_reason values: why a shot is not valid. Values from 3 are those the waveform gives
// (waveform_metrics.hpp); 5 and up are kept for more (saturated).
enum QualityReason : std::uint8_t {
  reason_none = 0,
  reason_off_terrain = 1,  // the beam's axis met no terrain: off the DEM, or into a nodata hole
  reason_nodata = 2,       // it met the terrain, but nodata or the DEM's edge is within 3 sigma
  reason_no_signal = 3,    // no band's waveform rises above its threshold
  reason_low_signal = 4,   // no band's peak stands low_signal_sigmas above the detector's noise
};

struct ShotRecord {
  std::int64_t shot_number = 0;
  std::int64_t source_shot_number = 0;                // the instrument's (a granule's), Footprint's
  double time_s = 0.0;                                // seconds since 2000-01-01T12:00:00Z
  double lat_deg = 0.0, lon_deg = 0.0, elev_m = 0.0;  // footprint centre
  double sc_lat_deg = 0.0, sc_lon_deg = 0.0, sc_alt_m = 0.0;  // spacecraft
  double off_nadir_deg = 0.0, range_m = 0.0;
  double slope_deg = 0.0, aspect_deg = 0.0;
  double elev_bin0_m = 0.0, elev_lastbin_m = 0.0;
  std::uint8_t quality_flag = quality_good;
  std::uint8_t quality_reason = reason_none;
  // The granule track's GEDI beam (its number: BEAM0101 is 5; kNoBeam for other tracks) and
  // degrade_flag; the sun at the footprint (deg, geometric; footprints/solar_position.hpp).
  std::uint8_t beam = kNoBeam;
  std::uint8_t degrade_flag = 0;
  double solar_elevation_deg = std::numeric_limits<double>::quiet_NaN();
  double solar_azimuth_deg = std::numeric_limits<double>::quiet_NaN();

  // [band][bin], W. Fill (NaN) when quality_flag is not good.
  std::vector<std::vector<double>> rx_waveform_W;
  std::vector<std::vector<double>> rx_waveform_canopy_W;  // last scattering on vegetation
  std::vector<std::vector<double>> rx_waveform_ground_W;  // last scattering on the ground
  // [band][order-1][bin], W; empty unless output.per_order.
  std::vector<std::vector<std::vector<double>>> rx_waveform_order_W;

  // [band]
  std::vector<double> rx_energy_J, rx_energy_canopy_J, rx_energy_ground_J;
  std::vector<double> reflectance;  // seed eq. (1)

  // Waveform processing of rx_waveform (pipeline/products/waveform_metrics.hpp), [band].
  // Elevations are m above WGS84; NaN where the waveform has no signal.
  std::vector<double> energy_tr_J, energy_cr_J, energy_gr_J;  // the seed's TR, CR, GR
  std::vector<double> waveform_index;                         // seed eq. (3)
  std::vector<double> sig_begin_m, sig_end_m, centroid_m;
  std::vector<std::int32_t> n_peaks;
  // [band][gaussian], 6 slots in waveform order, NaN where unused.
  std::vector<std::vector<double>> gauss_amp_W, gauss_center_m, gauss_sigma_ns, gauss_area_J;
  std::vector<double> ground_elev_est_m, canopy_height_est_m;
  std::vector<std::vector<double>> rh_m;  // [band][101]: rh0..rh100 above ground_elev_est

  // The footprint's truth from the scene, beam-weighted (NaN when unknown; 0 on bare ground).
  double cover_true = std::numeric_limits<double>::quiet_NaN();
  double pai_true = std::numeric_limits<double>::quiet_NaN();
  double canopy_height_true_m = std::numeric_limits<double>::quiet_NaN();
  // The beam's part that vertical lines carry through the vegetation to the ground (1 on bare
  // ground): the gap probability GEDI L2B's cover is one minus.
  double pgap_true = std::numeric_limits<double>::quiet_NaN();
  // [band], with an `atmosphere` section only (else empty, and not written): the layers' two-way
  // transmission, the part of the return they scattered and its extra path (shot_transport.hpp).
  std::vector<double> atmosphere_transmission, atmosphere_scattered_fraction, atmosphere_delay_m;

  // The beam's 1/e^2 contour on the terrain: closed ring of (lon, lat), counter-clockwise.
  std::vector<std::array<double, 2>> footprint_lonlat;

  // Photon events of a photon-counting receiver, as many a shot as it detected (none from the
  // waveform receiver), one entry each, the five of the same length. Stored in shots.nc as CF
  // contiguous ragged arrays along the `photon` dimension, counted by photon_count.
  std::vector<double> photon_time_ns;  // two-way time after the return from range_m (bin clock)
  std::vector<double> photon_lat_deg, photon_lon_deg, photon_h_m;  // where it was scattered
  std::vector<std::int32_t> photon_class;  // PhotonClass: what it came from (simulation truth)
  std::vector<std::int32_t> photon_order;  // its scattering order (truth); 0 for noise
};

// photon_class values: what a detected photon was last scattered by, or noise.
enum PhotonClass : std::int32_t {
  photon_noise = 0,          // background light or detector noise
  photon_ground = 1,         // last scattered by the ground
  photon_canopy = 2,         // last scattered by vegetation
  photon_top_of_canopy = 3,  // vegetation, in the top tenth of the canopy's return
};

// What every shot of a run shares.
struct RunInfo {
  std::string command_line;    // the `history` attribute
  std::string config_json;     // resolved configuration
  std::string vertical_datum;  // what the terrain's heights were measured from, in words
  std::uint64_t seed = 0;
  std::int64_t shots = 0;  // records the products will hold
  std::vector<ProductBand> bands;
  std::vector<double> bin_time_ns;                 // [bin] centre, after the return from range_m
  std::vector<double> tx_time_ns;                  // [tx_bin] centre, about the pulse peak
  std::vector<std::vector<double>> tx_waveform_W;  // [band][tx_bin]
  int orders = 0;                                  // per-order output: orders 1..orders; 0 when off
  bool photon_events = false;  // the records carry photon events (the `photon` dimension)
  bool atmosphere = false;     // an `atmosphere` section: its truth fields are written
  // Digitiser counts per W of recorded power, for the granules' waveforms in counts: the
  // detector's gain x (2^bits - 1) / saturation_W when it digitises, else 1 count per nW.
  double counts_per_W = 1e9;
  // The detector's gain (detector.gain) when the detector applies; NaN without one (GLAH14's
  // i_gval_rcv is then fill).
  double detector_gain = std::numeric_limits<double>::quiet_NaN();
  // The digitiser's full scale in counts (2^bits - 1) when it clips; 0 when nothing clips.
  double full_scale_counts = 0.0;
  // When the products were made (SOURCE_DATE_EPOCH's time where set: then they hold no wall-clock
  // measurement, so that identical runs write identical files); empty: the writer's clock.
  CreationTime created;
};

struct RunStats {
  std::int64_t ray_queries = 0;
  double wall_s = 0.0;
  std::int64_t shots_flagged = 0;
};

}  // namespace glaswave
