// The atmosphere's presets and the optical depths they are made of (atmosphere_presets.hpp).
#include "pipeline/config/atmosphere_presets.hpp"

#include <array>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace glaswave {

namespace {

// The molecules' number density falls by e in about 8 km near the ground (US Standard
// Atmosphere 1976); the column is cut into slabs above the ellipsoid that hold its share, so that
// a ground at 2 km sees the column above it alone (the transport cuts the layers at the scene).
constexpr double molecular_scale_height_m = 8000.0;
constexpr std::array<double, 7> molecular_slabs_m = {0, 1000, 2000, 4000, 8000, 16000, 50000};

// A boundary layer's aerosol (Hess, Koepke and Schult 1998, OPAC: the optical depths at 550 nm
// of the continental clean and continental polluted mixtures at 80 % relative humidity, and the
// polluted one's single-scattering albedo 0.89 and asymmetry 0.70; the clean one's, without soot,
// scatters more), with Angstrom's (1929) typical exponent 1.3, in the lowest 2 km above the
// ground.
struct Aerosol {
  double tau_550, alpha, albedo, g;
};
constexpr Aerosol clear_aerosol{0.064, 1.3, 0.97, 0.70};
constexpr Aerosol haze_aerosol{0.327, 1.3, 0.89, 0.70};
constexpr double boundary_layer_top_m = 2000.0;

AtmosphereLayer layer(double base_m, double top_m, bool above_ellipsoid, std::size_t bands) {
  AtmosphereLayer l;
  l.base_m = base_m;
  l.top_m = top_m;
  l.above_ellipsoid = above_ellipsoid;
  l.optical_depth.assign(bands, 0.0);
  l.single_scattering_albedo.assign(bands, 1.0);
  return l;
}

AtmospherePhase henyey_greenstein(double g) {
  AtmospherePhase p;
  p.kind = AtmospherePhase::Kind::henyey_greenstein;
  p.g1 = g;
  return p;
}

void add_molecules(std::vector<AtmosphereLayer>& layers, const std::vector<LidarBand>& bands) {
  for (std::size_t i = 0; i + 1 < molecular_slabs_m.size(); ++i) {
    const double z0 = molecular_slabs_m[i], z1 = molecular_slabs_m[i + 1];
    // The top slab holds what lies above it too: the column adds up to the whole.
    const double share =
        std::exp(-z0 / molecular_scale_height_m) -
        (i + 2 == molecular_slabs_m.size() ? 0.0 : std::exp(-z1 / molecular_scale_height_m));
    AtmosphereLayer l = layer(z0, z1, true, bands.size());
    for (std::size_t b = 0; b < bands.size(); ++b)
      l.optical_depth[b] = share * rayleigh_optical_depth(bands[b].wavelength_nm);
    layers.push_back(std::move(l));
  }
}

void add_aerosol(std::vector<AtmosphereLayer>& layers, const Aerosol& a,
                 const std::vector<LidarBand>& bands) {
  AtmosphereLayer l = layer(0.0, boundary_layer_top_m, false, bands.size());
  for (std::size_t b = 0; b < bands.size(); ++b) {
    l.optical_depth[b] = angstrom_optical_depth(a.tau_550, a.alpha, bands[b].wavelength_nm);
    l.single_scattering_albedo[b] = a.albedo;
  }
  l.phase = henyey_greenstein(a.g);
  layers.push_back(std::move(l));
}

// A cloud of large particles: its optical depth and albedo the same at 532 and 1064 nm.
void add_cloud(std::vector<AtmosphereLayer>& layers, double base_m, double top_m,
               bool above_ellipsoid, double tau, double g, const std::vector<LidarBand>& bands) {
  AtmosphereLayer l = layer(base_m, top_m, above_ellipsoid, bands.size());
  l.optical_depth.assign(bands.size(), tau);
  l.phase = henyey_greenstein(g);
  layers.push_back(std::move(l));
}

}  // namespace

const std::vector<std::string>& atmosphere_preset_names() {
  static const std::vector<std::string> names = {"clear", "haze", "cirrus", "stratus"};
  return names;
}

double rayleigh_optical_depth(double wavelength_nm) {
  const double lambda_um = wavelength_nm * 1e-3;
  const double inverse_square = 1.0 / (lambda_um * lambda_um);
  // Peck and Reeder (1972) for 300 ppm CO2 (Bodhaine's eq. 4), scaled to 360 ppm (eq. 19).
  constexpr double co2 = 360e-6;  // parts per volume
  const double n300_minus_1 =
      1e-8 * (5791817.0 / (238.0185 - inverse_square) + 167909.0 / (57.362 - inverse_square));
  const double n = 1.0 + n300_minus_1 * (1.0 + 0.54 * (co2 - 0.0003));
  // The King factor (eqs. 5, 6, 23), from Bates (1984): N2, O2, Ar, CO2 by volume in percent.
  const double f_n2 = 1.034 + 3.17e-4 * inverse_square;
  const double f_o2 =
      1.096 + 1.385e-3 * inverse_square + 1.448e-4 * inverse_square * inverse_square;
  const double co2_percent = co2 * 100.0;
  const double king = (78.084 * f_n2 + 20.946 * f_o2 + 0.934 * 1.00 + co2_percent * 1.15) /
                      (78.084 + 20.946 + 0.934 + co2_percent);
  // The cross-section per molecule (eq. 2), cm^2; Ns at 288.15 K and 1013.25 hPa, per cm^3.
  constexpr double ns = 2.546899e19;
  const double lambda_cm = lambda_um * 1e-4;
  const double n2 = n * n;
  const double sigma_cm2 = 24.0 * std::pow(std::numbers::pi, 3) * (n2 - 1.0) * (n2 - 1.0) /
                           (std::pow(lambda_cm, 4) * ns * ns * (n2 + 2.0) * (n2 + 2.0)) * king;
  // tau = sigma P A / (m_a g) (eq. 28): P in dyn/cm^2, m_a of dry air with its CO2 (eq. 17) in
  // g/mol, g in cm/s^2 at 45 degrees and the column's mass-weighted height z_c (eqs. 10, 11).
  constexpr double pressure_dyn_cm2 = 1013.25e3;
  constexpr double avogadro = 6.0221367e23;
  const double molar_mass = 15.0556 * co2 + 28.9595;
  const double z_c_m = 0.73737 * 0.0 + 5517.56;
  const double g0 = 980.6160;  // at 45 degrees: cos(2 phi) = 0
  const double g =
      g0 - 3.085462e-4 * z_c_m + 7.254e-11 * z_c_m * z_c_m - 1.517e-17 * std::pow(z_c_m, 3);
  return sigma_cm2 * pressure_dyn_cm2 * avogadro / (molar_mass * g);
}

double angstrom_optical_depth(double tau_550, double alpha, double wavelength_nm) {
  return tau_550 * std::pow(wavelength_nm / 550.0, -alpha);
}

std::vector<AtmosphereLayer> atmosphere_preset(const std::string& name,
                                               const std::vector<LidarBand>& bands) {
  std::vector<AtmosphereLayer> layers;
  add_molecules(layers, bands);
  if (name == "haze") {
    add_aerosol(layers, haze_aerosol, bands);
    return layers;
  }
  add_aerosol(layers, clear_aerosol, bands);
  // A thin cirrus at the upper bound of Sassen and Cho's (1992) class (0.03 to 0.3), with ice
  // crystals' forward peak (g 0.75 to 0.8 in the visible).
  if (name == "cirrus") add_cloud(layers, 9000.0, 11000.0, true, 0.3, 0.77, bands);
  // A low stratus of water droplets (g about 0.85).
  if (name == "stratus") add_cloud(layers, 500.0, 1500.0, false, 2.0, 0.85, bands);
  if (name != "clear" && name != "cirrus" && name != "stratus")
    throw std::invalid_argument("no atmosphere preset \"" + name + "\"");
  return layers;
}

}  // namespace glaswave
