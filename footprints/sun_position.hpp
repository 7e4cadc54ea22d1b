// Where the sun stands seen from a point of the Earth at a given time: what sets the solar
// background of a photon-counting receiver (and the solar angles the granules record).
#pragma once

namespace glaswave {

struct SunPosition {
  double elevation_deg = 0.0;  // above the horizon, geometric (no refraction)
  double azimuth_deg = 0.0;    // clockwise from north, in [0, 360)
};

// The Astronomical Almanac's low-precision solar coordinates (also Michalsky 1988, Solar Energy
// 40:227), about 0.01 degree over 1950-2050: from the days n since J2000.0, the mean longitude
// L = 280.460 + 0.9856474 n and mean anomaly g = 357.528 + 0.9856003 n give the ecliptic
// longitude L + 1.915 sin g + 0.020 sin 2g, the obliquity 23.439 - 4e-7 n gives right ascension
// and declination, and Greenwich mean sidereal time 18.697374558 h + 24.06570982441908 h n the
// hour angle at the longitude. The time is seconds since 2000-01-01T12:00:00Z (J2000.0, the GLAS
// epoch of the products), UT standing for TT (a 69 s difference moves the sun by 0.0008 degree).
SunPosition sun_position(double seconds_since_glas_epoch, double lat_deg, double lon_deg);

}  // namespace glaswave
