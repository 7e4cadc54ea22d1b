// What the transport tests share: the lidar of the seed's Table 2, typed from the table.
#pragma once

#include "pipeline/transport/lidar_model.hpp"

namespace glaswave::test_support {

// Table 2 of the seed: a 5 ns pulse, 0.11 mrad beam, 0.4 mrad field of view, a 0.95 m telescope
// (0.709 m^2), 1 ns bins, 544 of them; 32 mJ at 532 nm and 72 mJ at 1064 nm with round-trip
// transmissions 0.8 and 0.9.
inline LidarSettings table2_sensor() {
  LidarSettings sensor;
  sensor.pulse_sigma_ns = 5.0;
  sensor.divergence_sigma_rad = 0.00011;
  sensor.ifov_rad = 0.0004;
  sensor.telescope_area_m2 = 0.709;
  sensor.bin_ns = 1.0;
  sensor.bins = 544;
  sensor.bands = {{532.0, 32.0, 0.8}, {1064.0, 72.0, 0.9}};
  return sensor;
}

}  // namespace glaswave::test_support
