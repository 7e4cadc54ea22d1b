// Where the sun stands, seen from a place on the Earth at a time: the solar elevation and
// azimuth that GEDI's L1B and L2A products carry per shot (geolocation/solar_elevation,
// solar_azimuth), computed with ERFA (the IAU's SOFA in C, Debian's liberfa).
#pragma once

namespace glaswave {

struct SolarPosition {
  double elevation_deg = 0.0;  // above the horizon, without refraction
  double azimuth_deg = 0.0;    // clockwise from north, in [0, 360)
};

// The sun's topocentric position at `time_s` (seconds since 2000-01-01T12:00:00Z, counted without
// leap seconds as GLAS time stamps are) from the WGS84 point (lat_deg, lon_deg, height_m).
// The sun's barycentric place comes from ERFA's Earth ephemeris (eraEpv00) and is taken to the
// observer by eraAtco13: light time, aberration, precession-nutation, Earth rotation and the
// sun's parallax seen from the observer (8.8"), with UT1 = UTC (|UT1 - UTC| < 0.9 s moves the sun
// less than 0.004 deg) and no polar motion; no refraction, as GEDI's geometric angles. Against
// NREL's SPA (Reda and Andreas 2004, +-0.0003 deg) it agrees to within 0.001 deg
// (tests/footprints/solar_position_test.cpp). Throws std::invalid_argument for a non-finite
// input or a time outside the years 1900-2100.
SolarPosition solar_position(double time_s, double lat_deg, double lon_deg, double height_m = 0.0);

// The same for shot after shot, at a twentieth of its cost: what depends on the time alone and
// changes slowly (the Earth's ephemeris, precession-nutation, the CIO locator: 95 % of the cost)
// is evaluated exactly at whole minutes of the time stamps and interpolated linearly in TT
// between them, the rest (the Earth's rotation, the observer, aberration, parallax) exactly at
// each call. The Earth's acceleration over a minute moves it 3 m from the chord and the nutation
// bends less, so the angles stay within 1e-9 deg of solar_position's
// (tests/footprints/solar_position_test.cpp), a millionth of its 0.001 deg against SPA.
// The result depends on the arguments alone: the minutes met last are kept per thread, not
// shared. Throws as solar_position does.
SolarPosition solar_position_interpolated(double time_s, double lat_deg, double lon_deg,
                                          double height_m = 0.0);

}  // namespace glaswave
