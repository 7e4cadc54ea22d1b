// The lidar through the atmosphere's layers (issue 40), against numbers computed here without the
// transport: Beer-Lambert for an absorbing layer, and the single scattering of a thin
// Henyey-Greenstein layer (its part of the return and its delay) by quadrature.
#include "pipeline/transport/atmosphere.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "pipeline/transport/shot_transport.hpp"
#include "terrain/ground_mesh.hpp"
#include "terrain/terrain.hpp"

namespace glaswave {
namespace {

constexpr double pi = std::numbers::pi;

// Level Lambertian ground of reflectance 0.3 seen at nadir from `altitude_m`.
struct GroundShot {
  GroundShot(const LidarSettings& sensor, double altitude_m, double half_size_m)
      : lidar(sensor), scene(device, build_ground_mesh(plane, frame, half_size_m, 1.0e9)) {
    geometry.sensor_m = {0.0, 0.0, altitude_m};
    geometry.axis = {0.0, 0.0, -1.0};
    geometry.range_m = altitude_m;
    optics.soil_reflectance.assign(sensor.bands.size(), 0.3);
  }
  ShotWaveforms run(const TransportOptions& options) const {
    return simulate_shot(scene, lidar, geometry, optics, options, 3);
  }
  LidarModel lidar;
  PlaneTerrain plane{{0.0, 0.0, 0.0, 0.0, 0.0}};
  LocalFrame frame{{0.0, 0.0, 0.0}};
  RayDevice device;
  Scene scene;
  ShotGeometry geometry;
  SceneOptics optics;
};

AtmosphereLayer layer(double base_m, double top_m, std::vector<double> tau, double albedo,
                      AtmospherePhase phase) {
  AtmosphereLayer l;
  l.base_m = base_m;
  l.top_m = top_m;
  l.single_scattering_albedo.assign(tau.size(), albedo);
  l.optical_depth = std::move(tau);
  l.phase = phase;
  return l;
}

AtmospherePhase hg(double g) { return {AtmospherePhase::Kind::henyey_greenstein, g, 0.0, 1.0}; }

// Energy-weighted mean time (ns) and total of a shot's scored energies in band 0.
struct Moments {
  double energy_J = 0.0, mean_ns = 0.0;
};
Moments moments(const ShotWaveforms& w, const LidarModel& lidar) {
  Moments m;
  for (std::size_t i = 0; i < w.scored.size(); ++i) {
    const double e = w.scored.total_J[0][i];
    m.energy_J += e;
    m.mean_ns += e * lidar.bin_time_ns(static_cast<int>(w.scored.bins[i]) - lidar.margin_bins());
  }
  m.mean_ns /= m.energy_J;
  return m;
}

// A layer that only absorbs (single-scattering albedo 0) passes exp(-tau / mu) of the light each
// way: the return is exp(-2 tau) of the clear one at nadir (the rays' mu differ from 1 by 2e-8 at
// most in Table 2's field of view), band by band; the bands' fixed transmission is not applied.
TEST(Atmosphere, APurelyAbsorbingLayerPassesBeerLambertBothWays) {
  LidarSettings sensor;
  sensor.bands = {{532.0, 32.0, 1.0, "532"}, {1064.0, 72.0, 1.0, "1064"}};
  const GroundShot shot(sensor, 600000.0, 200.0);
  TransportOptions options;
  options.rays = 4000;
  const ShotWaveforms clear = shot.run(options);
  const std::vector<double> tau = {0.3, 0.1};
  options.atmosphere = AtmosphereSettings{"", {layer(2000.0, 3000.0, tau, 0.0, hg(0.8))}};
  const ShotWaveforms hazy = shot.run(options);
  for (std::size_t band = 0; band < 2; ++band)
    EXPECT_NEAR(hazy.energy_J[band] / clear.energy_J[band], std::exp(-2.0 * tau[band]), 1e-7)
        << band;
}

// The shot's truth through an absorbing layer seen 30 degrees off nadir: its transmission is
// exp(-2 tau / mu), mu = cos 30, and the return is that of the clear one (the rays' mu spread
// over GLAS's 0.2 mrad half view by 0.67 x 2e-4 in 1 / mu, which moves the ratio by 1e-4 at most
// and by far less on average); nothing scattered, so no delay and no scattered part.
TEST(Atmosphere, AnAbsorbingLayersTruthIsBeerLambertOffNadirWithoutDelay) {
  LidarSettings sensor;
  sensor.bands = {{532.0, 32.0, 1.0, "532"}, {1064.0, 72.0, 1.0, "1064"}};
  GroundShot shot(sensor, 600000.0, 400.0);
  const double angle = 30.0 * pi / 180.0, mu = std::cos(angle);
  shot.geometry.sensor_m = {600000.0 * std::tan(angle), 0.0, 600000.0};
  shot.geometry.range_m = norm(shot.geometry.sensor_m);
  shot.geometry.axis = (-1.0 / shot.geometry.range_m) * shot.geometry.sensor_m;
  TransportOptions options;
  options.rays = 4000;
  const ShotWaveforms clear = shot.run(options);
  EXPECT_TRUE(clear.atmosphere_transmission.empty());
  const std::vector<double> tau = {0.3, 0.1};
  options.atmosphere = AtmosphereSettings{"", {layer(2000.0, 3000.0, tau, 0.0, hg(0.8))}};
  const ShotWaveforms hazy = shot.run(options);
  ASSERT_EQ(hazy.atmosphere_transmission.size(), 2u);
  for (std::size_t band = 0; band < 2; ++band) {
    const double expected = std::exp(-2.0 * tau[band] / mu);
    EXPECT_NEAR(hazy.atmosphere_transmission[band], expected, 1e-12 * expected) << band;
    EXPECT_NEAR(hazy.energy_J[band] / clear.energy_J[band], expected, 1e-4 * expected) << band;
    EXPECT_EQ(hazy.atmosphere_scattered_fraction[band], 0.0) << band;
    EXPECT_EQ(hazy.atmosphere_delay_m[band], 0.0) << band;
  }
}

// The single scattering of a thin layer at height H (quadrature, exact geometry) over level
// Lambertian ground, sensor at Z at nadir, Gaussian beam truncated at the field of view:
//   clear  C = E_beam[cos^3 theta]                                   (return of a lit point)
//   down   D = E_beam[(tau/mu0) Int_{P in view} p(psi) cos^3(theta_P) dOmega_Q(P)]
//   up     U = E_beam[Int_{d in view} (tau/|d_z|) p(psi) cos(P->Q) Z^2 / |PQ|^2 dOmega_d]
// The return is exp(-2 tau) (C + D + U) / C of the clear one (to first order in tau), and its
// mean time the mean of the three parts' paths (L->P->L, L->Q->P->L, L->P->Q->L).
struct SingleScattering {
  double clear = 0.0, down = 0.0, up = 0.0;
  double clear_path_m = 0.0, down_path_m = 0.0, up_path_m = 0.0;  // weighted sums of paths
  // Weighted sums of the scattered paths' excess over the straight way to the lit point and back.
  double down_extra_m = 0.0, up_extra_m = 0.0;
};

SingleScattering single_scattering(double Z, double H, double tau, double g, double sigma,
                                   double half_fov) {
  SingleScattering s;
  const int nb = 60, nr = 120, nphi = 120;
  const double fraction = 1.0 - std::exp(-half_fov * half_fov / (2.0 * sigma * sigma));
  const Vec3 L{0.0, 0.0, Z};
  auto hgp = [g](double c) {
    const double d = 1.0 + g * g - 2.0 * g * c;
    return (1.0 - g * g) / (4.0 * pi * d * std::sqrt(d));
  };
  for (int ib = 0; ib < nb; ++ib) {
    // The beam's angle: its radial density (truncated Gaussian), by the midpoint rule on theta
    // (the azimuth is the ground's symmetry).
    const double t0 = (ib + 0.5) * half_fov / nb;
    const double w0 = t0 / (sigma * sigma) * std::exp(-t0 * t0 / (2.0 * sigma * sigma)) / fraction *
                      (half_fov / nb);
    const Vec3 d0{std::sin(t0), 0.0, -std::cos(t0)};
    const Vec3 P0 = L + (Z / std::cos(t0)) * d0;  // the lit point
    const double c3 = std::pow(std::cos(t0), 3);
    s.clear += w0 * c3;
    s.clear_path_m += w0 * c3 * 2.0 * norm(P0 - L);
    const Vec3 Q0 = L + ((Z - H) / std::cos(t0)) * d0;  // where the beam crosses the layer
    // Down: every ground point P in view, from Q0.
    const double R = Z * std::tan(half_fov);
    for (int ir = 0; ir < nr; ++ir)
      for (int ip = 0; ip < nphi; ++ip) {
        const double r = (ir + 0.5) * R / nr, phi = (ip + 0.5) * 2.0 * pi / nphi;
        const Vec3 P{r * std::cos(phi), r * std::sin(phi), 0.0};
        const Vec3 QP = P - Q0;
        const double dist = norm(QP);
        const double domega = (R / nr) * r * (2.0 * pi / nphi) * (H / dist) / (dist * dist);
        const double cosP = Z / norm(P - L);
        const double w =
            w0 * tau / std::cos(t0) * hgp(dot(d0, QP) / dist) * domega * std::pow(cosP, 3);
        s.down += w;
        s.down_path_m += w * (norm(Q0 - L) + dist + norm(P - L));
        s.down_extra_m += w * (norm(Q0 - L) + dist - norm(P - L));
      }
    // Up: every detector direction d in view, scattering at Q on it toward the detector.
    for (int ir = 0; ir < nr; ++ir)
      for (int ip = 0; ip < nphi; ++ip) {
        const double b = (ir + 0.5) * half_fov / nr, phi = (ip + 0.5) * 2.0 * pi / nphi;
        const Vec3 d{std::sin(b) * std::cos(phi), std::sin(b) * std::sin(phi), -std::cos(b)};
        const double domega = std::sin(b) * (half_fov / nr) * (2.0 * pi / nphi);
        const Vec3 Q = L + ((Z - H) / std::cos(b)) * d;
        const Vec3 PQ = Q - P0;
        const double dist = norm(PQ);
        const double w = w0 * tau / std::cos(b) * hgp(dot(PQ, -1.0 * d) / dist) * (H / dist) * Z *
                         Z / (dist * dist) * domega;
        s.up += w;
        s.up_path_m += w * (norm(P0 - L) + dist + norm(Q - L));
        s.up_extra_m += w * (dist + norm(Q - L) - norm(P0 - L));
      }
  }
  return s;
}

// A thin Henyey-Greenstein layer (g 0.8, tau 0.02, albedo 1) 1 km above the ground, seen from
// 3 km with a wide field of view (0.1 rad), so that much of its forward scattering stays in view:
// the return exceeds exp(-2 tau) of the clear one by the single-scattering fraction D + U (0.73 %
// by quadrature; the transport gives 0.72 %), and arrives later by its energy-weighted delay
// (0.124 ns; the transport 0.125 ns). Tolerances: 6 % of the fraction and of
// the delay (the forward-scattered photons are some 0.01 of 4e5 rays: 2.5 % of D's part in one
// standard deviation; double scattering, (D + U)^2, is 0.1 %; bins of 0.25 ns).
TEST(Atmosphere, AThinForwardScatteringLayerAddsItsSingleScatteringAndDelay) {
  const double Z = 3000.0, H = 1000.5, tau = 0.02, g = 0.8;
  LidarSettings sensor;
  sensor.divergence_sigma_rad = 0.01;
  sensor.ifov_rad = 0.1;
  sensor.pulse_sigma_ns = 0.5;
  sensor.bin_ns = 0.25;
  sensor.bins = 2400;
  sensor.bands = {{1064.0, 72.0, 1.0, "1064"}};
  const GroundShot shot(sensor, Z, 1500.0);
  TransportOptions options;
  options.rays = 400000;
  options.max_order = 1;
  options.power_waveforms = false;
  options.scored_energies = true;
  const Moments clear = moments(shot.run(options), shot.lidar);
  options.atmosphere = AtmosphereSettings{"", {layer(1000.0, 1001.0, {tau}, 1.0, hg(g))}};
  const ShotWaveforms truth = shot.run(options);
  const Moments hazy = moments(truth, shot.lidar);

  const SingleScattering s =
      single_scattering(Z, H, tau, g, sensor.divergence_sigma_rad, 0.5 * sensor.ifov_rad);
  const double fraction = (s.down + s.up) / s.clear;
  const double gain = hazy.energy_J / clear.energy_J / std::exp(-2.0 * tau) - 1.0;
  EXPECT_GT(fraction, 0.005);
  EXPECT_NEAR(gain, fraction, 0.06 * fraction);
  const double c_m_ns = speed_of_light_m_s * 1e-9;
  const double expected_delay_ns =
      ((s.clear_path_m + s.down_path_m + s.up_path_m) / (s.clear + s.down + s.up) -
       s.clear_path_m / s.clear) /
      c_m_ns;
  EXPECT_GT(expected_delay_ns, 0.1);
  EXPECT_NEAR(hazy.mean_ns - clear.mean_ns, expected_delay_ns, 0.06 * expected_delay_ns);
  // The shot's truth: the scattered part (D + U) / (C + D + U); its delay the scattered paths'
  // mean excess over the straight way to the same lit point and back (0.027 m by quadrature; less
  // than the mean time's shift, 0.037 m, as the down-scattered light lands across the whole view,
  // whose edge is 3.7 m farther than its centre from 3 km); the direct transmission exp(-2 tau).
  const double scattered = (s.down + s.up) / (s.clear + s.down + s.up);
  EXPECT_NEAR(truth.atmosphere_scattered_fraction[0], scattered, 0.06 * scattered);
  const double extra_m = (s.down_extra_m + s.up_extra_m) / (s.clear + s.down + s.up);
  EXPECT_NEAR(truth.atmosphere_delay_m[0], extra_m, 0.06 * extra_m);
  EXPECT_NEAR(truth.atmosphere_transmission[0], std::exp(-2.0 * tau), 1e-12);
}

// A thin cirrus (tau 0.3, g 0.77) at 10 km over a footprint seen from 600 km (GLAS's 0.4 mrad
// field of view, R = 120 m on the ground): a forward-scattered photon that stays in view has
// gone at most about (2R)^2 / (2H) further (scattered at one edge of the view, landing at the
// other), on average R^2 / (4H) (phase function flat over the 24 mrad in view, the lit spot and
// the scattering point small against the view): no return later than 2 R^2 / H, and a tail of
// mean delay below R^2 / (2H) = 0.72 m. Only light scattered twice (in the 1 km thick layer, or
// on both ways) arrives beyond the bound: 2 % of the tail here, tested below 5 %.
TEST(Atmosphere, ACirrusDelaysTheTailByAtMostTheFieldOfViewsBound) {
  const double Z = 600000.0, H = 10000.0;
  LidarSettings sensor;
  sensor.divergence_sigma_rad = 0.0000275;
  sensor.pulse_sigma_ns = 0.5;
  sensor.bin_ns = 0.1;
  sensor.bins = 600;
  sensor.bands = {{1064.0, 72.0, 1.0, "1064"}};
  const GroundShot shot(sensor, Z, 400.0);
  TransportOptions options;
  options.rays = 100000;
  options.max_order = 1;
  options.power_waveforms = false;
  options.scored_energies = true;
  options.atmosphere = AtmosphereSettings{"", {layer(H - 500.0, H + 500.0, {0.3}, 1.0, hg(0.77))}};
  const ShotWaveforms w = shot.run(options);
  const double R = Z * std::tan(0.5 * sensor.ifov_rad);
  const double c_m_ns = speed_of_light_m_s * 1e-9;
  // The lit spot's own spread of range is 1.2 cm (Z theta^2 / 2): two bins hold the direct part.
  const double bound_m = 2.0 * R * R / (H - 500.0) + sensor.bin_ns * c_m_ns;
  double tail_J = 0.0, tail_m = 0.0, beyond_J = 0.0;
  for (std::size_t i = 0; i < w.scored.size(); ++i) {
    const double t_ns =
        shot.lidar.bin_time_ns(static_cast<int>(w.scored.bins[i]) - shot.lidar.margin_bins());
    const double extra_m = t_ns * c_m_ns;
    if (extra_m <= 0.1) continue;
    tail_J += w.scored.total_J[0][i];
    tail_m += w.scored.total_J[0][i] * extra_m;
    if (extra_m > bound_m) beyond_J += w.scored.total_J[0][i];
  }
  ASSERT_GT(tail_J, 0.0);
  EXPECT_LT(beyond_J, 0.05 * tail_J);
  EXPECT_LT(tail_m / tail_J, R * R / (2.0 * H));
  // The shot's truth: the scattered light's mean extra path (delay over scattered part) is
  // within the same bound, and the scattered part holds at least the bins' tail.
  const double fraction = w.atmosphere_scattered_fraction[0];
  ASSERT_GT(fraction, 0.0);
  EXPECT_GT(w.atmosphere_delay_m[0], 0.0);
  EXPECT_LT(w.atmosphere_delay_m[0] / fraction, R * R / (2.0 * H));
  double total_J = 0.0;
  for (const double e : w.scored.total_J[0]) total_J += e;
  EXPECT_GE(fraction, tail_J / total_J);
}

}  // namespace
}  // namespace glaswave
