// Units of length as files write them (a DEM band's unit type, a NetCDF variable's `units`), and
// units of plant area density (an area per volume: a length to the power -1).
#pragma once

#include <optional>
#include <string_view>

namespace glaswave {

// Metres per unit: m, dm, cm, mm, km, ft and US survey ft, spelt as files spell them ("metre",
// "US survey foot"...), case and surrounding spaces aside; "" is metres; empty for a unit not
// known here.
std::optional<double> metres_per_unit(std::string_view unit);

// m^-1 per unit of a plant area density written as UDUNITS writes one: terms of a length unit
// and its power, apart by spaces, '.', '*' or '/' ("m2 m-3", "cm2 cm-3", "m^2/m^3", "m-1",
// "1/m"), the powers adding to -1. "" is m2 m-3. Empty for anything else (a unit not known, or
// no length to the power -1: "m2 m-2").
std::optional<double> per_metre_per_density_unit(std::string_view unit);

}  // namespace glaswave
