// ATL03- and ATL08-like HDF5 granules (PRODUCT.md section 9) in the layout ICESat-2's users read:
// per beam gtXY, ATL03's heights/ per photon and geolocation/ 20 m segments with 1-based photon
// index ranges, ATL08's land_segments/ of 100 m from the photons' own classification and
// signal_photons/ linking each classified photon back to ATL03, the simulation's truth beside
// them. Each file is written under a temporary name and renamed when complete.
#pragma once

#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "pipeline/products/atl08_classification.hpp"

namespace glaswave {

// Seconds from the GLAS epoch (2000-01-01T12:00:00Z) to the ATLAS standard data product epoch
// (2018-01-01T00:00:00Z), both counted without leap seconds: 6574.5 days.
inline constexpr double atlas_epoch_since_glas_epoch_s = 6574.5 * 86400.0;
// GPS seconds of the ATLAS epoch, ATL03's ancillary_data/atlas_sdp_gps_epoch.
inline constexpr double atlas_sdp_gps_epoch_s = 1198800018.0;

// One recorded photon of a beam.
struct BeamPhoton {
  double h_m = 0.0;  // above the WGS84 ellipsoid
  double lat_deg = 0.0, lon_deg = 0.0;
  double delta_time_s = 0.0;     // since the ATLAS epoch
  std::uint8_t truth_class = 0;  // 0 background, 1 ground, 2 canopy, 3 top of canopy
  std::uint8_t order = 0;        // scattering order, 0 for background
};

// One shot of a beam: where it fell and what the simulation knows there.
struct BeamShot {
  double along_m = 0.0;  // along-track distance from the track's start
  double lat_deg = 0.0, lon_deg = 0.0, delta_time_s = 0.0;
  double ground_h_m = 0.0;       // the terrain at the footprint centre
  double canopy_height_m = 0.0;  // the simulation's truth over the footprint
  double canopy_cover = 0.0, pai = 0.0, pgap = 0.0;
  double background_rate_Hz = 0.0;   // the background photons' rate in the receiver (ATL03's
                                     // bckgrd_atlas/bckgrd_rate): measured by ATLAS, here known
  double solar_elevation_deg = 0.0;  // the sun above the footprint's horizon (NaN: unknown)
  double solar_azimuth_deg = std::numeric_limits<double>::quiet_NaN();  // clockwise from north
  // The spacecraft (WGS84) and its range to the footprint centre, NaN where not known.
  double sc_lat_deg = std::numeric_limits<double>::quiet_NaN();
  double sc_lon_deg = std::numeric_limits<double>::quiet_NaN();
  double sc_alt_m = std::numeric_limits<double>::quiet_NaN();
  double range_m = std::numeric_limits<double>::quiet_NaN();
  std::uint32_t first_photon = 0, photon_count = 0;  // its photons in BeamTrack::photons
};

// One beam's shots (in time order) and their photons (shot by shot, each shot's in time order).
struct BeamTrack {
  std::string name;  // gt1l ... gt3r
  bool strong = true;
  int spot_number = 1;    // ATLAS's spot, 1-6
  double across_m = 0.0;  // its ground track right of the reference ground track's
  double pulse_energy_J = std::numeric_limits<double>::quiet_NaN();  // its transmitted pulse's
  // Photons detected per joule of the band's whole pulse's return (NaN: not known, not written).
  double photons_per_J = std::numeric_limits<double>::quiet_NaN();
  std::vector<BeamShot> shots;
  std::vector<BeamPhoton> photons;
};

// One beam of the granules: its group, its strength and ATLAS's spot.
struct GranuleBeam {
  std::string name = "gt2l";
  bool strong = true;
  int spot_number = 3;
  double across_m = 0.0;  // its ground track right of the reference ground track's
  double pulse_energy_J = std::numeric_limits<double>::quiet_NaN();  // NaN: not known, fill
  double photons_per_J = std::numeric_limits<double>::quiet_NaN();   // BeamTrack's
};

// ATL03's orbit_info/sc_orient: 0 backward, 1 forward (footprints/atlas_beams.hpp's
// AtlasOrientation), which decides the beams' strengths and spots.
inline constexpr std::int8_t atlas_sc_orient_backward = 0;
inline constexpr std::int8_t atlas_sc_orient_forward = 1;

// Which ICESat-2 granules a run writes, and for which beams (in the granules' order). With
// several beams a record belongs to the one whose spot number is its ShotRecord::beam; one beam
// takes every record.
// A cloud or aerosol layer of the simulated atmosphere that ATL09's layer finder would report
// (pipeline/transport/atmosphere.hpp's detected_layers): its base above the ground under the
// segment, or above the WGS84 ellipsoid.
struct CloudLayer {
  double base_m = 0.0;
  bool above_ellipsoid = false;
};

struct Icesat2ProductSettings {
  bool atl03 = false;
  bool atl08 = false;
  std::vector<GranuleBeam> beams = {GranuleBeam{}};
  std::int8_t sc_orient = atlas_sc_orient_backward;
  double dead_time_ns = 3.2;  // each detector channel's (sensor.dead_time_ns)
  // With an `atmosphere` section, its reported layers (maybe none); without, absent.
  std::optional<std::vector<CloudLayer>> cloud_layers;
};

struct GranuleInfo {
  std::string history;  // the command line
  std::string config_json;
  std::int8_t sc_orient = atlas_sc_orient_backward;
  double dead_time_ns = std::numeric_limits<double>::quiet_NaN();  // NaN: not known, fill
  // The transmitted pulse, ATL03's transmitter echo path histogram: its times about the peak
  // (ns) and power (any scale); empty: not known, fill.
  std::vector<double> pulse_time_ns, pulse_power;
  // ATL08's msw_flag, layer_flag and cloud_flag_atm come from these (Icesat2ProductSettings).
  std::optional<std::vector<CloudLayer>> cloud_layers;
};

// DIR/atl03.h5. Per beam: heights/{h_ph, lat_ph, lon_ph, delta_time, dist_ph_along,
// dist_ph_across, quality_ph, signal_conf_ph (photons x 5 surface types, the land column from the
// classification, -1 "not considered" in the others), glaswave_truth_class, glaswave_order};
// geolocation/ 20 m segments {segment_id (1-based from the track start), ph_index_beg (1-based,
// 0 when empty), segment_ph_cnt, segment_dist_x, segment_length, reference_photon_lat,
// reference_photon_lon, delta_time, solar_elevation, sigma_h}; geophys_corr/{dem_h, delta_time};
// bckgrd_atlas/{bckgrd_rate, delta_time} per shot. Both granules: ancillary_data/
// {atlas_sdp_gps_epoch, data_start_utc, data_end_utc}, orbit_info/{sc_orient, sc_orient_time,
// rgt, cycle_number} (docs/icesat2.md lists each field's source). Throws Error (run) on a failed
// write.
void write_atl03(const std::filesystem::path& path, const std::vector<BeamTrack>& beams,
                 const std::vector<Atl08Classes>& classes, const GranuleInfo& info);

// DIR/atl08.h5. Per beam: land_segments/{latitude, longitude, delta_time, segment_id_beg,
// segment_id_end, dem_h, solar_elevation, snr, night_flag, terrain_flg, msw_flag, layer_flag,
// ph_removal_flag, sat_flag, terrain/{h_te_best_fit, h_te_mean, h_te_median, h_te_min, h_te_max,
// h_te_uncertainty, terrain_slope, n_te_photons}, canopy/{h_canopy, canopy_openness,
// h_mean_canopy, h_mean_canopy_abs, h_min_canopy, h_median_canopy, h_max_canopy,
// canopy_h_metrics (segments x 18), h_canopy_uncertainty, n_ca_photons, n_toc_photons}, the 20 m
// sub-segments' latitude_20m, longitude_20m, terrain/{h_te_best_fit_20m, subset_te_flag} and
// canopy/{h_canopy_20m, subset_can_flag} (segments x 5), glaswave_truth/{h_te, h_canopy,
// canopy_cover, pai, pgap}}; signal_photons/{classed_pc_flag, classed_pc_indx, ph_segment_id,
// ph_h, d_flag, delta_time}.
void write_atl08(const std::filesystem::path& path, const std::vector<BeamTrack>& beams,
                 const std::vector<Atl08Classes>& classes, const Atl08Settings& settings,
                 const GranuleInfo& info);

// The classification of each beam's photons (CloudPhoton: the shot's along-track distance, the
// photon's height, the shot's background rate over the track's mean shot spacing), in the beams'
// order.
std::vector<Atl08Classes> classify_beams(const std::vector<BeamTrack>& beams,
                                         const Atl08Settings& settings);

}  // namespace glaswave
