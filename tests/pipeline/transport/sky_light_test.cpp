// The sky's light for the photon-counting background (issue 40) against closed forms: through a
// layer that only absorbs, the background is the transmission formula's, exactly; the light a
// thin Henyey-Greenstein layer scatters toward the receiver is its single scattering,
//   R_path = omega pi p(Theta) (1 - e^(-tau (1 / mu0 + 1))) / (mu0 + 1)   (nadir view),
// and a conservative layer's albedo from below is 1 less what it lets through.
#include "pipeline/transport/sky_light.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "pipeline/transport/photon_counting.hpp"
#include "tests/pipeline/transport/transport_test_support.hpp"

namespace glaswave {
namespace {

using test_support::uniform_layer;

constexpr double pi = std::numbers::pi;

double hg_phase(double g, double c) {
  const double d = 1.0 + g * g - 2.0 * g * c;
  return (1.0 - g * g) / (4.0 * pi * d * std::sqrt(d));
}

// An absorbing layer of tau 0.4: no light of its own, the sun's and the scene's direct alone
// (exp(-tau / mu0), exp(-tau)), nothing sent back down; the background rate is then the
// transmission formula's with T = exp(-tau), at every sun and reflectance, to 1e-12.
TEST(SkyLight, AbsorbingLayerGivesTheTransmissionFormula) {
  const double tau = 0.4;
  const SkyLight sky =
      sky_light(AtmosphereSettings{"", {uniform_layer(0.0, 3000.0, tau, {0.0}, {})}}, 1, 0, 7, 200);
  ASSERT_EQ(sky.mu_sun.size(), 20u);
  for (std::size_t k = 0; k < sky.mu_sun.size(); ++k) {
    EXPECT_NEAR(sky.down_transmission[k], std::exp(-tau / sky.mu_sun[k]), 1e-12);
    EXPECT_EQ(sky.path_reflectance[k], 0.0);
  }
  EXPECT_NEAR(sky.up_transmission, std::exp(-tau), 1e-12);
  EXPECT_EQ(sky.spherical_albedo, 0.0);
  for (double zenith_deg : {0.0, 30.0, 60.0})  // nodes at cos 1 and 0.5; 30 degrees between
    for (double rho : {0.1, 0.6}) {
      SolarBackground b;
      b.sun_zenith_deg = zenith_deg;
      b.reflectance = rho;
      b.transmission_one_way = std::exp(-tau);
      b.filter_bandwidth_nm = 0.038;
      b.ifov_rad = 83e-6;
      b.telescope_area_m2 = 0.41;
      b.efficiency = 0.0675;
      const double fixed = background_rate_Hz(b);
      b.sky = &sky;
      const double through = background_rate_Hz(b);
      const double tolerance = zenith_deg == 30.0 ? 2e-3 : 1e-12;  // linear between nodes
      EXPECT_NEAR(through / fixed, 1.0, tolerance) << zenith_deg << " " << rho;
    }
}

// A thin HG layer (tau 0.2, g 0.7); band 1 scatters a thousandth of band 0's light, so its light
// is single scattering (its weight drops a thousandfold at each scattering: at 0.01 the twice
// scattered light was 0.5 % of it at these suns, 4 % with the sun overhead, where the layer's
// backscatter is 180 times weaker than its forward peak), within the Monte Carlo's 0.6 %.
TEST(SkyLight, ThinLayerPathLightIsItsSingleScattering) {
  const double tau = 0.2, g = 0.7, omega = 0.001;
  const AtmospherePhase phase{AtmospherePhase::Kind::henyey_greenstein, g, 0.0, 1.0};
  const SkyLight sky =
      sky_light(AtmosphereSettings{"", {uniform_layer(1000.0, 2000.0, tau, {1.0, omega}, phase)}},
                2, 1, 7, 100000);
  for (std::size_t k : {4u, 9u}) {  // sun cosines 0.25 and 0.5
    const double mu0 = sky.mu_sun[k];
    // The light arrives going down at mu0 and leaves straight up: cos(Theta) = -mu0.
    const double expected =
        omega * pi * hg_phase(g, -mu0) * -std::expm1(-tau * (1.0 / mu0 + 1.0)) / (mu0 + 1.0);
    RecordProperty("path_" + std::to_string(k), std::to_string(sky.path_reflectance[k]));
    RecordProperty("expected_" + std::to_string(k), std::to_string(expected));
    EXPECT_NEAR(sky.path_reflectance[k] / expected, 1.0, 0.02) << mu0;
  }
}

// A conservative layer (omega 1) absorbs nothing: of the scene's Lambertian light going up, what
// does not come back down (S) leaves, and leaves as the sun's light at the same cosines comes
// down (reciprocity): S = 1 - 2 int_0^1 T_down(mu) mu dmu, the integral by the table's nodes
// (trapezoids, T_down(0) = 0), to 0.01.
TEST(SkyLight, ConservativeLayerAlbedoFromBelowIsWhatItDoesNotLetThrough) {
  const AtmospherePhase phase{AtmospherePhase::Kind::henyey_greenstein, 0.8, 0.0, 1.0};
  const SkyLight sky = sky_light(
      AtmosphereSettings{"", {uniform_layer(1000.0, 2000.0, 1.0, {1.0}, phase)}}, 1, 0, 7, 20000);
  double through = 0.0, mu = 0.0, f = 0.0;
  for (std::size_t k = 0; k < sky.mu_sun.size(); ++k) {
    const double next = sky.down_transmission[k] * sky.mu_sun[k];
    through += 0.5 * (f + next) * (sky.mu_sun[k] - mu);
    mu = sky.mu_sun[k];
    f = next;
  }
  RecordProperty("spherical_albedo", std::to_string(sky.spherical_albedo));
  RecordProperty("expected", std::to_string(1.0 - 2.0 * through));
  EXPECT_GT(sky.spherical_albedo, 0.05);
  EXPECT_NEAR(sky.spherical_albedo, 1.0 - 2.0 * through, 0.01);
}

}  // namespace
}  // namespace glaswave
