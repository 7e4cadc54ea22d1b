// What the configuration says about the track: how shots are placed and pointed.
// Filled by pipeline/config, read by the footprints library.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace glaswave {

enum class TrackType { pass, points, orbit, ephemeris, granule };

struct GroundPoint {
  double lat_deg = 0.0;
  double lon_deg = 0.0;
};

// Mean Keplerian elements at `epoch`, in the true-equator mean-equinox frame of date (as
// two-line elements), propagated with J2 secular rates (footprints/orbit.hpp).
struct OrbitElements {
  double semi_major_axis_m = 6978137.0;
  double eccentricity = 0.0;
  double inclination_deg = 94.0;
  double raan_deg = 0.0;
  double arg_perigee_deg = 0.0;
  double mean_anomaly_deg = 0.0;
  double epoch_s = 0.0;  // seconds since the GLAS epoch, 2000-01-01T12:00:00Z
};

struct TrackSettings {
  TrackType type = TrackType::pass;
  double start_lat_deg = 0.0;
  double start_lon_deg = 0.0;
  double heading_deg = 0.0;
  std::int64_t shots = 1;  // pass; orbit: shots in its time sequence, kept where on the terrain
  double rate_hz = 40.0;
  std::optional<double> spacing_m;  // unset: from rate_hz and the ground speed
  double altitude_m = 600000.0;
  double start_time_s = 0.0;  // seconds since the GLAS epoch, 2000-01-01T12:00:00Z
  double off_nadir_deg = 0.0;
  double pointing_azimuth_deg = 0.0;
  std::vector<GroundPoint> points;  // type points
  OrbitElements orbit;              // type orbit
  std::string ephemeris;            // type ephemeris: CSV path (format in footprints/ephemeris.hpp)
  std::string granule;              // type granule: HDF5 path (layouts in footprints/granule.hpp)
  std::vector<std::string> beams;   // type granule: the beams (groups) to take; empty: all
};

}  // namespace glaswave
