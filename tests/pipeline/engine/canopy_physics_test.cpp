// PHYSICS.md sections 3, 4 and 6 for vegetation: a homogeneous turbid layer (the RAMI HOM case)
// against its closed-form single scattering, the omega^k scaling of scattering orders, the
// n^-1/2 error law, and the seed's base-case forest. Expected values are computed here.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "footprints/track.hpp"
#include "pipeline/engine/inputs.hpp"
#include "tests/pipeline/engine/engine_test_support.hpp"

namespace glaswave {
namespace {

constexpr double pi = std::numbers::pi;
constexpr double c_m_s = 299792458.0;

struct Simulated {
  ShotRecord record;
  std::vector<double> bin_time_ns;
  double normalisation_J;  // E_t T A_T f_fov / (pi R^2): a Lambertian reflectance of 1 at nadir
};

Simulated simulate(const nlohmann::json& document) {
  test_support::SimulatedTrack run = test_support::simulate_track(document);
  const SensorSettings& s = run.config.sensor;
  const double f_fov = 1.0 - std::exp(-s.ifov_rad * s.ifov_rad /
                                      (8.0 * s.divergence_sigma_rad * s.divergence_sigma_rad));
  const double range_m = run.footprints.at(0).range_m;
  const LidarBand& band = s.bands.at(0);
  const double normalisation_J = band.pulse_energy_mJ * 1e-3 * band.atmos_transmission_roundtrip *
                                 s.telescope_area_m2 * f_fov / (pi * range_m * range_m);
  return {run.records.at(0), run.bin_time_ns, normalisation_J};
}

// PHYSICS.md section 3, single scattering of a layer with L = 3, rho = 0.45, rho_s = 0.3:
// point leaves (rho/3)(1 - e^-L) and rho_s e^-L; finite leaves (2 rho/3)(1 - e^-L/2) and
// rho_s e^-L/2 (the hotspot). To 2 %.
TEST(TurbidLayer, SingleScatteringMatchesClosedForms) {
  const double L = 3.0, rho = 0.45, soil = 0.3;
  struct Case {
    double leaf_size_m, canopy, ground;
  };
  const Case cases[] = {
      {0.0, rho / 3.0 * (1.0 - std::exp(-L)), soil * std::exp(-L)},
      {0.05, 2.0 * rho / 3.0 * (1.0 - std::exp(-L / 2.0)), soil * std::exp(-L / 2.0)},
  };
  EXPECT_NEAR(cases[0].canopy, 0.1425, 1e-4);  // the values PHYSICS.md quotes
  EXPECT_NEAR(cases[0].ground, 0.01494, 1e-5);
  EXPECT_NEAR(cases[1].canopy, 0.2331, 1e-4);
  EXPECT_NEAR(cases[1].ground, 0.06694, 1e-5);
  for (const Case& c : cases) {
    const Simulated shot =
        simulate(test_support::layer_shot(L, c.leaf_size_m, rho, 0.45, soil, 1, 40000));
    const double canopy = shot.record.rx_energy_canopy_J[0] / shot.normalisation_J;
    const double ground = shot.record.rx_energy_ground_J[0] / shot.normalisation_J;
    EXPECT_NEAR(canopy / c.canopy, 1.0, 0.02) << "leaf size " << c.leaf_size_m;
    // The footprint's truth: a layer covers everything with its PAI, 10 m tall.
    EXPECT_NEAR(shot.record.cover_true, 1.0, 1e-12);
    EXPECT_NEAR(shot.record.pai_true, L, 1e-6);
    // A vertical line's gap probability through spherical leaves (G = 1/2): e^-L/2, with G as
    // the transport's leaf-angle table gives it (within 2e-4 of 1/2: LeafAngles' test), so to
    // L e^-L/2 2e-4 = 1.3e-4.
    EXPECT_NEAR(shot.record.pgap_true, std::exp(-0.5 * L), 1.5e-4);
    // 1 cm: the slab is flat in the shot's frame, the ground curves away by d^2 / 2R (3 mm at
    // the footprint's 3 sigma, 200 m).
    EXPECT_NEAR(shot.record.canopy_height_true_m, 10.0, 0.01);
    EXPECT_NEAR(ground / c.ground, 1.0, 0.02) << "leaf size " << c.leaf_size_m;
  }
}

// simulation.sampling "sobol": the same closed forms (finite leaves, the hotspot) at a quarter
// of the rays, to the same 2 %: quasi-random points are unbiased and converge faster.
TEST(TurbidLayer, SobolSamplingMatchesTheClosedForms) {
  const double L = 3.0, rho = 0.45, soil = 0.3;
  nlohmann::json document = test_support::layer_shot(L, 0.05, rho, 0.45, soil, 1, 10000);
  document["simulation"]["sampling"] = "sobol";
  const Simulated shot = simulate(document);
  const double canopy = shot.record.rx_energy_canopy_J[0] / shot.normalisation_J;
  const double ground = shot.record.rx_energy_ground_J[0] / shot.normalisation_J;
  EXPECT_NEAR(canopy / (2.0 * rho / 3.0 * (1.0 - std::exp(-L / 2.0))), 1.0, 0.02);
  EXPECT_NEAR(ground / (soil * std::exp(-L / 2.0)), 1.0, 0.02);
}

// The single-scattering canopy return per unit depth z below the top: (u rho / 3) e^(-u z / 2)
// with the hotspot, (u rho / 3) e^(-u z) for point leaves (u = L / H). With a short pulse, the
// energy in each third of the layer's depth against the integral of that law.
TEST(TurbidLayer, CanopyReturnFollowsItsExponentialLawWithDepth) {
  const double L = 3.0, rho = 0.45, depth_m = 10.0, u = L / depth_m;
  for (double leaf_size_m : {0.0, 0.05}) {
    const double k = leaf_size_m > 0.0 ? u / 2.0 : u;  // attenuation per metre of depth
    nlohmann::json document = test_support::layer_shot(L, leaf_size_m, rho, 0.45, 0.0, 1, 40000);
    document["sensor"]["pulse_sigma_ns"] = 0.05;
    const Simulated shot = simulate(document);
    const auto& waveform = shot.record.rx_waveform_canopy_W[0];
    double simulated[3] = {0, 0, 0}, expected[3] = {0, 0, 0};
    for (std::size_t i = 0; i < waveform.size(); ++i) {
      // Bin i covers heights c (t +- 0.5 ns) / 2 above the ground; depth below the top.
      const double z0 = depth_m + c_m_s * (shot.bin_time_ns[i] - 0.5) * 1e-9 / 2.0;
      const double z1 = depth_m + c_m_s * (shot.bin_time_ns[i] + 0.5) * 1e-9 / 2.0;
      const double a = std::clamp(z0, 0.0, depth_m), b = std::clamp(z1, 0.0, depth_m);
      if (b <= a) continue;
      const int third = std::min(2, static_cast<int>(3.0 * (0.5 * (a + b)) / depth_m));
      simulated[third] += waveform[i] * 1e-9 / shot.normalisation_J;
      expected[third] += u * rho / 3.0 / k * (std::exp(-k * a) - std::exp(-k * b));
    }
    for (int third = 0; third < 3; ++third)
      EXPECT_NEAR(simulated[third] / expected[third], 1.0, 0.03)
          << "leaf size " << leaf_size_m << ", third " << third;
  }
}

// PHYSICS.md section 4: over black soil with rho : tau fixed, the energy of scattering order k
// scales as omega^k. One run per omega, to 3 %. With one seed and one rho : tau the two runs
// trace the same paths up to order 5 (no roulette yet), so this checks the weights each order
// carries, not the sampling; the sampling is checked against the integral below.
TEST(TurbidLayer, OrderEnergiesScaleAsOmegaToTheK) {
  const Simulated white = simulate(test_support::layer_shot(3.0, 0.05, 0.5, 0.5, 0.0, 5, 20000));
  const Simulated grey = simulate(test_support::layer_shot(3.0, 0.05, 0.3, 0.3, 0.0, 5, 20000));
  for (int k = 1; k <= 5; ++k) {
    double white_J = 0, grey_J = 0;
    for (double p : white.record.rx_waveform_order_W[0][k - 1]) white_J += p;
    for (double p : grey.record.rx_waveform_order_W[0][k - 1]) grey_J += p;
    ASSERT_GT(white_J, 0.0) << k;
    EXPECT_NEAR(grey_J / white_J / std::pow(0.6, k), 1.0, 0.03) << "order " << k;
  }
}

// Second order of a layer of point leaves over black soil, at nadir, against the plane-parallel
// integral computed here: light scattered at depth z1 into direction mu (cosine with up), carried
// to depth z2, scattered up there and out, with Gamma of PHYSICS.md section 3 at both ends:
//   R2 = pi 2pi int dmu int dz2 e^(-k z2) (u/pi) Gamma(beta2) (u/pi) Gamma(beta1) I(z2, mu),
// k = G u, cos beta1 = -mu (from straight down), cos beta2 = mu (to straight up), and I the
// first leg integrated over z1 in closed form. The field of view (0.8 mrad) takes in the light
// spread by the second order. To 2 %.
TEST(TurbidLayer, SecondOrderMatchesThePlaneParallelIntegral) {
  const double L = 3.0, depth_m = 10.0, rho = 0.45, tau = 0.45, u = L / depth_m, k = 0.5 * u;
  auto gamma = [&](double cos_beta) {
    const double beta = std::acos(std::clamp(cos_beta, -1.0, 1.0));
    return (rho + tau) / (3 * pi) * (std::sin(beta) - beta * cos_beta) + tau / 3 * cos_beta;
  };
  // First leg: from every z1 above (mu < 0) or below (mu > 0) to z2, per unit of the source.
  auto first_leg = [&](double z2, double mu) {
    // (1/m) int e^(-k z1) e^(-k |z2 - z1| / m) dz1, written so that no exponent grows.
    const double m = std::abs(mu);
    if (mu < 0) {
      const double a = k * (1 / m - 1);
      return a > 1e-12 ? (std::exp(-k * z2) - std::exp(-k * z2 / m)) / (a * m)
                       : z2 * std::exp(-k * z2);
    }
    const double b = k * (1 + 1 / m);
    return std::exp(-k * z2) * -std::expm1(-b * (depth_m - z2)) / (b * m);
  };
  const int steps = 2000;
  double r2 = 0.0;
  for (int i = 0; i < steps; ++i) {
    const double mu = -1.0 + (i + 0.5) * 2.0 / steps;
    for (int j = 0; j < steps; ++j) {
      const double z2 = (j + 0.5) * depth_m / steps;
      r2 += std::exp(-k * z2) * (u / pi) * gamma(mu) * (u / pi) * gamma(-mu) * first_leg(z2, mu) *
            (2.0 / steps) * (depth_m / steps);
    }
  }
  r2 *= pi * 2 * pi;
  nlohmann::json document = test_support::layer_shot(L, 0.0, rho, tau, 0.0, 2, 40000);
  document["sensor"]["ifov_rad"] = 0.0008;
  const Simulated shot = simulate(document);
  double second_J = 0.0;
  for (double p : shot.record.rx_waveform_order_W[0][1]) second_J += p * 1e-9;
  EXPECT_NEAR(second_J / shot.normalisation_J / r2, 1.0, 0.02) << "R2 = " << r2;
}

// Per-order waveforms do not change with max_order (PHYSICS.md section 8), and the orders add
// up to the total.
TEST(TurbidLayer, OrdersDoNotDependOnMaxOrderAndSumToTheTotal) {
  const Simulated three = simulate(test_support::layer_shot(3.0, 0.05, 0.45, 0.45, 0.3, 3, 5000));
  const Simulated eight = simulate(test_support::layer_shot(3.0, 0.05, 0.45, 0.45, 0.3, 8, 5000));
  for (int k = 0; k < 3; ++k) {
    const auto& a = three.record.rx_waveform_order_W[0][k];
    const auto& b = eight.record.rx_waveform_order_W[0][k];
    for (std::size_t i = 0; i < a.size(); ++i)
      EXPECT_NEAR(a[i], b[i], 1e-9 * (std::abs(a[i]) + 1e-30)) << k;
  }
  double total = 0, orders = 0;
  for (double p : eight.record.rx_waveform_W[0]) total += p;
  for (const auto& order : eight.record.rx_waveform_order_W[0])
    for (double p : order) orders += p;
  EXPECT_NEAR(orders / total, 1.0, 1e-9);
}

// PHYSICS.md section 6: the error falls as n^-1/2. The RMS difference of the waveform from a
// reference run of 256 times the rays, for n, 4n and 16n rays (several seeds each): the slope
// on a log-log plot is -0.5 +- 0.05. A layer, so that the scene does not change with the seed.
TEST(TurbidLayer, ErrorFallsAsTheInverseSquareRootOfTheRays) {
  auto waveform = [](std::int64_t rays, int seed) {
    nlohmann::json document = test_support::layer_shot(3.0, 0.05, 0.45, 0.45, 0.3, 8, rays);
    document["seed"] = seed;
    return simulate(document).record.rx_waveform_W[0];
  };
  const std::vector<double> reference = waveform(160000, 1000);
  std::vector<double> log_n, log_rms;
  for (std::int64_t rays : {625, 2500, 10000}) {
    double squares = 0;
    int count = 0;
    for (int seed = 1; seed <= 6; ++seed) {
      const std::vector<double> w = waveform(rays, seed);
      for (std::size_t i = 0; i < w.size(); ++i, ++count)
        squares += (w[i] - reference[i]) * (w[i] - reference[i]);
    }
    log_n.push_back(std::log(static_cast<double>(rays)));
    log_rms.push_back(0.5 * std::log(squares / count));
  }
  // Least-squares slope through the three points.
  const double mean_x = (log_n[0] + log_n[1] + log_n[2]) / 3,
               mean_y = (log_rms[0] + log_rms[1] + log_rms[2]) / 3;
  double sxy = 0, sxx = 0;
  for (int i = 0; i < 3; ++i) {
    sxy += (log_n[i] - mean_x) * (log_rms[i] - mean_y);
    sxx += (log_n[i] - mean_x) * (log_n[i] - mean_x);
  }
  EXPECT_NEAR(sxy / sxx, -0.5, 0.05);
}

// The seed's base case (Tables 1 and 2): a two-peaked waveform, the canopy's single scattering
// from the crowns' heights (bases 15-20 m, 16 m tall: 15-36 m) and the ground return at the
// ground. (Multiple scattering travels further and shows below the crowns.)
TEST(BaseForest, TwoPeaksWithTheCanopyAboveTheGround) {
  nlohmann::json document = {
      {"seed", 1},
      {"sensor", {{"preset", "north2010"}}},
      {"terrain", {{"plane", {{"origin_lat_deg", 45.0}, {"origin_lon_deg", 7.0}}}}},
      {"canopy", nlohmann::json::object()},  // Table 1's defaults
      {"track", {{"type", "points"}, {"points", {{{"lat_deg", 45.0}, {"lon_deg", 7.0}}}}}},
  };
  const Simulated shot = simulate(document);
  document["simulation"]["max_order"] = 1;
  const Simulated single = simulate(document);
  const auto& total = shot.record.rx_waveform_W[1];
  const auto& canopy = single.record.rx_waveform_canopy_W[1];
  const auto& ground = shot.record.rx_waveform_ground_W[1];
  auto height_m = [&](std::size_t i) { return -c_m_s * shot.bin_time_ns[i] * 1e-9 / 2.0; };
  double canopy_sum = 0, canopy_inside = 0, ground_sum = 0, ground_moment = 0;
  for (std::size_t i = 0; i < total.size(); ++i) {
    canopy_sum += canopy[i];
    // The pulse spreads returns by 0.75 m RMS: allow 3 of them about the crowns' span.
    if (height_m(i) > 15.0 - 2.25 && height_m(i) < 36.0 + 2.25) canopy_inside += canopy[i];
    ground_sum += ground[i];
    ground_moment += ground[i] * height_m(i);
  }
  EXPECT_GT(canopy_inside / canopy_sum, 0.97);
  EXPECT_NEAR(ground_moment / ground_sum, 0.0, 1.0);
  // Peaks: the highest bin among the crowns and among the ground, and a dip between them.
  double canopy_peak = 0, ground_peak = 0, dip = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < total.size(); ++i) {
    const double h = height_m(i);
    if (h > 15.0 && h < 36.0) canopy_peak = std::max(canopy_peak, total[i]);
    if (std::abs(h) < 2.0) ground_peak = std::max(ground_peak, total[i]);
    if (h > 4.0 && h < 12.0) dip = std::min(dip, total[i]);
  }
  EXPECT_LT(dip, 0.5 * canopy_peak);
  EXPECT_LT(dip, 0.5 * ground_peak);
  EXPECT_GT(canopy_sum, ground_sum);  // 70 % cover, PAI 3: mostly canopy return
}

// PHYSICS.md section 4: at the seed's settings (n = 10^4, Tables 1 and 2) the orders converge by
// order 8: each order after the second brings less than the one before, and the eighth less
// than 1 % of the total.
TEST(BaseForest, ScatteringOrdersConvergeByTheEighth) {
  const nlohmann::json document = {
      {"seed", 2},
      {"sensor", {{"preset", "north2010"}}},
      {"terrain", {{"plane", {{"origin_lat_deg", 45.0}, {"origin_lon_deg", 7.0}}}}},
      {"canopy", nlohmann::json::object()},
      {"track", {{"type", "points"}, {"points", {{{"lat_deg", 45.0}, {"lon_deg", 7.0}}}}}},
      {"output", {{"per_order", true}}},
  };
  const Simulated shot = simulate(document);
  for (int band = 0; band < 2; ++band) {
    double total = 0, order_J[8] = {};
    for (int k = 0; k < 8; ++k)
      for (double p : shot.record.rx_waveform_order_W[band][k]) order_J[k] += p, total += p;
    for (int k = 2; k < 8; ++k)
      EXPECT_LT(order_J[k], order_J[k - 1]) << "band " << band << ", order " << k + 1;
    EXPECT_LT(order_J[7] / total, 0.01) << "band " << band;
  }
}

}  // namespace
}  // namespace glaswave
