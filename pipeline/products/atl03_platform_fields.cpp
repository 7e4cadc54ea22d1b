// ATL03's geolocation/ fields of the platform, the pulse and the range (atl03_platform_fields.hpp).
#include "pipeline/products/atl03_platform_fields.hpp"

#include <array>
#include <cmath>
#include <limits>
#include <numbers>

namespace glaswave {
namespace {

constexpr double kSpeedOfLight_m_s = 299792458.0;
constexpr double kWgs84A_m = 6378137.0, kWgs84E2 = 6.69437999014e-3;
constexpr float kFillFloat = std::numeric_limits<float>::max();

using Xyz = std::array<double, 3>;

Xyz ecef(double lat_deg, double lon_deg, double h_m) {
  const double lat = lat_deg * std::numbers::pi / 180.0, lon = lon_deg * std::numbers::pi / 180.0;
  const double n = kWgs84A_m / std::sqrt(1.0 - kWgs84E2 * std::sin(lat) * std::sin(lat));
  return {(n + h_m) * std::cos(lat) * std::cos(lon), (n + h_m) * std::cos(lat) * std::sin(lon),
          (n * (1.0 - kWgs84E2) + h_m) * std::sin(lat)};
}

float as_float(double v) { return std::isfinite(v) ? static_cast<float>(v) : kFillFloat; }

template <typename F>
std::vector<float> each(const std::vector<const BeamShot*>& shots, F get) {
  std::vector<float> values;
  values.reserve(shots.size());
  for (const BeamShot* shot : shots) values.push_back(as_float(get(*shot)));
  return values;
}

}  // namespace

PointingAngles pointing_to_spacecraft(const BeamShot& s) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (!std::isfinite(s.sc_lat_deg) || !std::isfinite(s.sc_lon_deg) || !std::isfinite(s.sc_alt_m) ||
      !std::isfinite(s.ground_h_m))
    return {nan, nan};
  const Xyz g = ecef(s.lat_deg, s.lon_deg, s.ground_h_m);
  const Xyz c = ecef(s.sc_lat_deg, s.sc_lon_deg, s.sc_alt_m);
  const Xyz d{c[0] - g[0], c[1] - g[1], c[2] - g[2]};
  const double lat = s.lat_deg * std::numbers::pi / 180.0,
               lon = s.lon_deg * std::numbers::pi / 180.0;
  const double east = -std::sin(lon) * d[0] + std::cos(lon) * d[1];
  const double north = -std::sin(lat) * std::cos(lon) * d[0] -
                       std::sin(lat) * std::sin(lon) * d[1] + std::cos(lat) * d[2];
  const double up = std::cos(lat) * std::cos(lon) * d[0] + std::cos(lat) * std::sin(lon) * d[1] +
                    std::sin(lat) * d[2];
  // A spacecraft straight above (within a millimetre, the positions' rounding) has no
  // azimuth: 0 there, not the rounding's direction.
  const double horizontal = std::hypot(east, north);
  return {std::atan2(up, horizontal), horizontal < 1e-3 ? 0.0 : std::atan2(east, north)};
}

std::vector<SegmentField> atl03_platform_fields(const BeamTrack& beam,
                                                const std::vector<const BeamShot*>& shots) {
  const std::size_t n = shots.size();
  const std::vector<float> zero(n, 0.0f), fill(n, kFillFloat);
  std::vector<double> altitude;
  for (const BeamShot* s : shots)
    altitude.push_back(std::isfinite(s->sc_alt_m) ? s->sc_alt_m
                                                  : std::numeric_limits<double>::max());
  std::vector<float> elevation, azimuth;
  for (const BeamShot* s : shots) {
    const PointingAngles a = pointing_to_spacecraft(*s);
    elevation.push_back(as_float(a.elevation_rad));
    azimuth.push_back(as_float(a.azimuth_rad));
  }
  const char* no_error = "0: the simulation places its photons without geolocation error";
  const char* no_attitude =
      "0: the simulated spacecraft keeps a fixed attitude; each beam's pointing is in "
      "ref_elev/ref_azimuth";
  const char* no_delay =
      "0: the simulation's light travels straight and in vacuum, so its heights need no "
      "neutral-atmosphere correction";
  return {
      {"altitude_sc", "meters", "altitude", "referenceInformation",
       "The spacecraft's height above the WGS84 ellipsoid at the segment's reference shot",
       altitude},
      {"bounce_time_offset", "seconds", "bounce time offset", "modelResult",
       "The one-way time from the spacecraft to the reference shot's footprint centre (its "
       "range over c)",
       each(shots, [](const BeamShot& s) { return s.range_m / kSpeedOfLight_m_s; })},
      {"full_sat_fract", "1", "full saturation fraction", "qualityInformation",
       "Fill: glaswave does not apply ATLAS's saturation classification", fill},
      {"near_sat_fract", "1", "near saturation fraction", "qualityInformation",
       "Fill: glaswave does not apply ATLAS's saturation classification", fill},
      {"neutat_delay_derivative", "meters/meter", "Change in neutral atmospheric delay per height",
       "modelResult", no_delay, zero},
      {"neutat_delay_total", "meters", "Total neutral atmosphere delay correction", "modelResult",
       no_delay, zero},
      {"neutat_ht", "meters", "Reference height of the neutral atmosphere range correction",
       "modelResult", "Fill: no neutral-atmosphere correction is computed", fill},
      {"pitch", "degrees", "spacecraft pitch", "modelResult", no_attitude, zero},
      {"podppd_flag", "1", "POD_PPD Flag", "qualityInformation",
       "0 nominal: the simulation's positions and pointing are exact",
       std::vector<std::int8_t>(n, 0)},
      {"range_bias_corr", "meters", "range bias correction", "modelResult",
       "0: the simulation has no range bias", zero},
      {"ref_azimuth", "radians", "azimuth", "modelResult",
       "Azimuth of the unit vector from the reference shot's footprint centre to the "
       "spacecraft in the local east-north-up frame, from north, east positive (0 with the "
       "spacecraft straight above)",
       azimuth},
      {"ref_elev", "radians", "elevation", "modelResult",
       "Elevation of that unit vector above the local east-north plane", elevation},
      {"roll", "degrees", "spacecraft roll", "modelResult", no_attitude, zero},
      {"sigma_across", "meters", "across-track geolocation uncertainty", "qualityInformation",
       no_error, zero},
      {"sigma_along", "meters", "along-track geolocation uncertainty", "qualityInformation",
       no_error, zero},
      {"sigma_lat", "degrees", "latitude uncertainty", "qualityInformation", no_error, zero},
      {"sigma_lon", "degrees", "longitude uncertainty", "qualityInformation", no_error, zero},
      {"solar_azimuth", "degrees_east", "solar azimuth", "modelResult",
       "The sun's azimuth at the reference shot's footprint, clockwise from north "
       "(footprints/solar_position)",
       each(shots, [](const BeamShot& s) { return s.solar_azimuth_deg; })},
      {"tx_pulse_energy", "Joules", "transmit pulse energy", "modelResult",
       "The beam's pulse: the first band's pulse_energy_mJ times the beam's ratio to a strong "
       "beam's (fill where not known)",
       std::vector<float>(n, as_float(beam.pulse_energy_J))},
      {"tx_pulse_skew_est", "seconds", "transmit pulse skew estimate", "modelResult",
       "0: the simulated pulse is a Gaussian, whose threshold crossings are centred on its peak "
       "at any threshold",
       zero},
      {"tx_pulse_width_lower", "seconds", "transmit pulse width lower", "modelResult",
       "Fill: ATLAS's start-pulse detector thresholds are not simulated", fill},
      {"tx_pulse_width_upper", "seconds", "transmit pulse width upper", "modelResult",
       "Fill: ATLAS's start-pulse detector thresholds are not simulated", fill},
      {"yaw", "degrees", "spacecraft yaw", "modelResult", no_attitude, zero},
  };
}

}  // namespace glaswave
