// ATL03's gtXY/geolocation/ fields of the platform, the pulse and the range, per 20 m segment:
// the 23 that ICESat2VegR's ATL03_seg_metadata_dt reads by default besides the segment's place
// and photons (carlos-alberto-silva/ICESat2VegR R/ATL03_seg_metadata_dt.R, its `attributes`
// default and ATL03.seg.map). Each is the value at the segment's reference shot, or what the
// simulation knows of it for every segment (docs/icesat2.md says which and why).
#pragma once

#include <cstdint>
#include <string>
#include <variant>
#include <vector>

#include "pipeline/products/icesat2_products.hpp"

namespace glaswave {

// One geolocation/ dataset: its name, attributes and one value a segment. Written with the
// type's largest value as _FillValue (float32 3.4028235e+38, float64 1.7976931348623157e+308,
// int8 127), the ATL03 dictionary's fills.
struct SegmentField {
  std::string name, units, long_name, content_type, description;
  std::variant<std::vector<double>, std::vector<float>, std::vector<std::int8_t>> values;
};

// The fields of `beam`'s segments whose reference shots are `shots` (one a segment, in order):
// altitude_sc, bounce_time_offset, full_sat_fract, near_sat_fract, neutat_delay_derivative,
// neutat_delay_total, neutat_ht, pitch, podppd_flag, range_bias_corr, ref_azimuth, ref_elev,
// roll, sigma_across, sigma_along, sigma_lat, sigma_lon, solar_azimuth, tx_pulse_energy,
// tx_pulse_skew_est, tx_pulse_width_lower, tx_pulse_width_upper, yaw.
std::vector<SegmentField> atl03_platform_fields(const BeamTrack& beam,
                                                const std::vector<const BeamShot*>& shots);

// The unit vector from a ground point to the spacecraft in the point's local east-north-up
// frame, as ATL03's ref_elev (above the east-north plane) and ref_azimuth (from north, east
// positive), radians; NaN where a position is not known.
struct PointingAngles {
  double elevation_rad, azimuth_rad;
};
PointingAngles pointing_to_spacecraft(const BeamShot& shot);

}  // namespace glaswave
