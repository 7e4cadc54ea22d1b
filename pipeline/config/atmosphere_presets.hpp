// The atmosphere's named presets (`"atmosphere": "clear"`, PRODUCT.md section 12), each expanded
// into layers for the run's bands by their wavelengths: the molecules by Bodhaine et al. (1999),
// a boundary-layer aerosol by an Angstrom law, and the clouds, whose optical depths hardly change
// between 532 and 1064 nm.
#pragma once

#include <string>
#include <vector>

#include "footprints/atmosphere_settings.hpp"
#include "footprints/lidar_settings.hpp"

namespace glaswave {

// "clear", "haze", "cirrus", "stratus".
const std::vector<std::string>& atmosphere_preset_names();

// The vertical Rayleigh optical depth of the molecular atmosphere from sea level (1013.25 hPa,
// 45 degrees latitude, 360 ppm CO2) at `wavelength_nm`, from first principles as Bodhaine et al.
// (1999, J. Atmos. Oceanic Technol. 16, 1854) recommend: Peck and Reeder's refractive index of
// air corrected for CO2, the King factor of N2, O2, Ar and CO2, and gravity at the column's
// mass-weighted height.
double rayleigh_optical_depth(double wavelength_nm);

// A boundary layer's aerosol optical depth at `wavelength_nm` from its value at 550 nm and its
// Angstrom exponent: tau_550 (lambda / 550)^-alpha.
double angstrom_optical_depth(double tau_550, double alpha, double wavelength_nm);

// The layers of preset `name` (one of atmosphere_preset_names()) for `bands`.
std::vector<AtmosphereLayer> atmosphere_preset(const std::string& name,
                                               const std::vector<LidarBand>& bands);

}  // namespace glaswave
