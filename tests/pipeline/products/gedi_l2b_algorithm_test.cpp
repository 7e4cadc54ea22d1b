// Tests of GEDI L2B's algorithm on waveforms made of Gaussians of known areas, whose canopy and
// ground integrals, gap probability, cover and PAI are known in closed form (Tang & Armston's
// ATBD: Pgap = 1 - Rv / (Rv + 1.5 Rg), PAI = -ln(Pgap) cos(theta) / 0.5), and whose profiles
// follow from the Gaussian's cumulative integral (erfc): the half-energy ground separation, the
// cumulative profiles from the top, foliage height diversity and the flags.
#include "pipeline/products/gedi_l2b_algorithm.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "pipeline/products/gedi_l2a_groups.hpp"

namespace glaswave {
namespace {

// 0.125 m a bin, so that the profile's 5 m edges fall on bins' edges (40 bins) when the ground
// does (x.5): the cumulative integrals there are sums of whole bins.
constexpr int kBins = 1100;
constexpr double kBinM = 0.125;
constexpr double kTopM = 1000.0;
const WaveformAxis kAxis{1.0, kTopM, kTopM - (kBins - 1) * kBinM};
constexpr double kGroundBin = 900.5;

double elevation(double bin) { return kTopM - bin * kBinM; }

// A Gaussian of `area` (waveform unit x bins) centred at `center` bins, sigma `sigma` bins.
GaussianComponent of_area(double area, double center, double sigma) {
  return {area / (sigma * std::sqrt(2.0 * std::numbers::pi)), center, sigma};
}

std::vector<double> waveform(const std::vector<GaussianComponent>& parts, double noise_mean) {
  std::vector<double> values(kBins, noise_mean);
  for (int i = 0; i < kBins; ++i)
    for (const GaussianComponent& g : parts) values[i] += g.value_at(i);
  return values;
}

// Phi(x): the standard normal's cumulative distribution.
double phi(double x) { return 0.5 * std::erfc(-x / std::numbers::sqrt2); }

GediL2bInput input_for(const std::vector<double>& values, double noise_mean, double begin_bin,
                       double end_bin, double zenith_rad) {
  GediL2bInput in;
  in.waveform = values;
  in.axis = kAxis;
  in.noise_mean = noise_mean;
  in.elev_highestreturn_m = elevation(begin_bin);
  in.elev_lowestmode_m = elevation(kGroundBin);
  in.elev_lowestreturn_m = elevation(end_bin);
  in.zenith_rad = zenith_rad;
  return in;
}

// Canopy (area 120, 20 m above the ground, sigma 2.5 m) over ground (area 80, sigma 0.75 m),
// each 8 sigma inside the signal's limits: Rv = 120 and Rg = 80 to ~1e-15, so Pgap = 1 -
// 120 / (120 + 1.5 x 80) = 0.5 exactly, cover 0.5, PAI = -2 cos(0.1) ln 0.5.
TEST(GediL2b, TwoGaussiansGiveTheClosedForms) {
  const double canopy_area = 120.0, ground_area = 80.0, noise = 7.0, zenith = 0.1;
  const double canopy_bin = kGroundBin - 160.0, canopy_sigma = 20.0, ground_sigma = 6.0;
  const auto values = waveform(
      {of_area(canopy_area, canopy_bin, canopy_sigma), of_area(ground_area, kGroundBin, 6.0)},
      noise);
  const GediL2bResult r = gedi_l2b(input_for(values, noise, canopy_bin - 8.0 * canopy_sigma,
                                             kGroundBin + 8.0 * ground_sigma, zenith));
  ASSERT_EQ(r.algorithmrun_flag, 1);
  EXPECT_EQ(r.l2b_quality_flag, 1);
  EXPECT_NEAR(r.rv, canopy_area, 1e-9);
  EXPECT_NEAR(r.rg, ground_area, 1e-9);
  const double pgap = 1.0 - canopy_area / (canopy_area + 1.5 * ground_area);
  EXPECT_NEAR(pgap, 0.5, 1e-15);
  EXPECT_NEAR(r.pgap_theta, pgap, 1e-12);
  EXPECT_NEAR(r.cover, 1.0 - pgap, 1e-12);
  EXPECT_NEAR(r.pai, -2.0 * std::cos(zenith) * std::log(pgap), 1e-12);
  EXPECT_DOUBLE_EQ(r.rhov, 0.6);
  EXPECT_DOUBLE_EQ(r.rhog, 0.4);
  EXPECT_DOUBLE_EQ(r.rossg, 0.5);
  EXPECT_DOUBLE_EQ(r.omega, 1.0);

  // The profiles: the canopy above z = 5k m is 120 Phi((x_k - canopy) / sigma), x_k its bin.
  // The sums of whole bins of a sampled Gaussian differ from Phi by the midpoint rule's
  // h^2 f' / 24 <= 0.003 (f' <= 120 x 0.24 / 20^2): 1e-4 in PAI.
  double pavd_sum = 0.0;
  for (int k = 0; k < kL2bProfileBins; ++k) {
    const double edge_bin = kGroundBin - k * kL2bDz_m / kBinM;
    const double rv_above =
        k == 0 ? canopy_area : canopy_area * phi((edge_bin - canopy_bin) / canopy_sigma);
    const double pgap_above = 1.0 - rv_above / (canopy_area + 1.5 * ground_area);
    EXPECT_NEAR(r.cover_z[k], 1.0 - pgap_above, 1e-4) << "k " << k;
    EXPECT_NEAR(r.pai_z[k], -2.0 * std::cos(zenith) * std::log(pgap_above), 1e-4) << "k " << k;
    pavd_sum += r.pavd_z[k] * kL2bDz_m;
  }
  EXPECT_DOUBLE_EQ(r.cover_z[0], r.cover);
  EXPECT_DOUBLE_EQ(r.pai_z[0], r.pai);
  EXPECT_NEAR(pavd_sum, r.pai, 1e-12);  // the profile sums to the total PAI
  // Nothing above 20 m + 8 sigma: the top bins are empty.
  EXPECT_NEAR(r.pai_z[kL2bProfileBins - 1], 0.0, 1e-12);
  // Pgap over the waveform's bins: 1 above the signal, pgap_theta at the ground.
  ASSERT_EQ(r.pgap_theta_z.size(), static_cast<std::size_t>(kBins));
  EXPECT_DOUBLE_EQ(r.pgap_theta_z[0], 1.0);
  EXPECT_NEAR(r.pgap_theta_z[901], r.pgap_theta, 1e-12);
}

// Understory inside the ground's upper half (1.5 m above it, sigma 0.5 m): the half-energy
// method takes the ground from below its centre alone, so Rg is the ground's area plus twice the
// understory's tail below the ground, Phi(-3) of it, and Rv the rest.
TEST(GediL2b, GroundIsTwiceTheEnergyBelowTheLowestMode) {
  const double canopy_area = 100.0, under_area = 30.0, ground_area = 60.0;
  const double under_bin = kGroundBin - 12.0, under_sigma = 4.0;
  const auto values =
      waveform({of_area(canopy_area, kGroundBin - 160.0, 20.0),
                of_area(under_area, under_bin, under_sigma), of_area(ground_area, kGroundBin, 6.0)},
               0.0);
  const GediL2bResult r =
      gedi_l2b(input_for(values, 0.0, kGroundBin - 320.0, kGroundBin + 48.0, 0.0));
  const double tail = under_area * phi(-(kGroundBin - under_bin) / under_sigma);
  // The whole-bin sum of the understory's tail differs from Phi by h^2 f' / 24 ~ 2e-3.
  EXPECT_NEAR(r.rg, ground_area + 2.0 * tail, 5e-3);
  EXPECT_NEAR(r.rv, canopy_area + under_area - 2.0 * tail, 5e-3);
  EXPECT_GT(2.0 * tail, 0.05);  // the tail is there to be seen: 0.081
}

// Two thin layers centred in the 10-15 m and 20-25 m bins, of areas making Pgap 0.8 below the
// first and 0.64 below both (D = Rv + 1.5 Rg = 100: 20, 16 and Rg = 64 / 1.5): equal PAI in two
// bins, so fhd_normal = ln 2, and pai_z between the layers is -2 ln 0.8.
TEST(GediL2b, TwoEqualLayersHaveFhdLn2) {
  const auto values =
      waveform({of_area(20.0, kGroundBin - 180.0, 4.0), of_area(16.0, kGroundBin - 100.0, 4.0),
                of_area(64.0 / 1.5, kGroundBin, 6.0)},
               0.0);
  const GediL2bResult r =
      gedi_l2b(input_for(values, 0.0, kGroundBin - 220.0, kGroundBin + 48.0, 0.0));
  EXPECT_NEAR(r.pgap_theta, 0.64, 1e-9);
  EXPECT_NEAR(r.pai, -2.0 * std::log(0.64), 1e-9);
  EXPECT_NEAR(r.pai_z[3], -2.0 * std::log(0.8), 1e-6);  // 15 m: below the upper layer alone
  EXPECT_NEAR(r.pavd_z[2] * kL2bDz_m, -2.0 * std::log(0.8), 1e-6);
  EXPECT_NEAR(r.pavd_z[4] * kL2bDz_m, -2.0 * std::log(0.8), 1e-6);
  EXPECT_NEAR(r.pavd_z[3], 0.0, 1e-6);
  // The layers leak Phi(-5) = 3e-7 of their area across their bins' edges.
  EXPECT_NEAR(r.fhd_normal, std::log(2.0), 1e-5);
}

TEST(GediL2b, BareGroundHasNoCover) {
  const auto values = waveform({of_area(50.0, kGroundBin, 6.0)}, 2.0);
  const GediL2bResult r =
      gedi_l2b(input_for(values, 2.0, kGroundBin - 48.0, kGroundBin + 48.0, 0.0));
  EXPECT_EQ(r.l2b_quality_flag, 1);
  EXPECT_NEAR(r.rg, 50.0, 1e-9);
  EXPECT_NEAR(r.rv, 0.0, 1e-9);
  EXPECT_NEAR(r.cover, 0.0, 1e-9);
  EXPECT_NEAR(r.pai, 0.0, 1e-9);
  EXPECT_TRUE(std::isnan(r.fhd_normal));  // no foliage: no distribution to be diverse
}

TEST(GediL2b, FlagsWhatCannotBeRetrieved) {
  const auto values = waveform({of_area(50.0, kGroundBin - 160.0, 6.0)}, 0.0);
  // The ground at the signal's end: no ground return, Pgap 0 and PAI unbounded.
  GediL2bInput in = input_for(values, 0.0, kGroundBin - 220.0, kGroundBin, 0.0);
  GediL2bResult r = gedi_l2b(in);
  EXPECT_EQ(r.algorithmrun_flag, 1);
  EXPECT_EQ(r.l2b_quality_flag, 0);
  EXPECT_NEAR(r.cover, 1.0, 1e-12);
  EXPECT_TRUE(std::isnan(r.pai));
  // No ground at all, or limits out of order: the algorithm does not run.
  in.elev_lowestmode_m = std::numeric_limits<double>::quiet_NaN();
  r = gedi_l2b(in);
  EXPECT_EQ(r.algorithmrun_flag, 0);
  EXPECT_TRUE(std::isnan(r.cover));
  in = input_for(values, 0.0, kGroundBin + 10.0, kGroundBin + 48.0, 0.0);
  EXPECT_EQ(gedi_l2b(in).algorithmrun_flag, 0);
  // L2A's own flag carries through.
  const auto bare = waveform({of_area(50.0, kGroundBin, 6.0)}, 0.0);
  in = input_for(bare, 0.0, kGroundBin - 48.0, kGroundBin + 48.0, 0.0);
  in.l2a_quality_flag = false;
  r = gedi_l2b(in);
  EXPECT_EQ(r.algorithmrun_flag, 1);
  EXPECT_EQ(r.l2b_quality_flag, 0);
}

// Another reflectance ratio and clumping are the caller's: Pgap = 1 - Rv / (Rv + (rhov / rhog)
// Rg), PAI divided by G Omega.
TEST(GediL2b, SettingsEnterTheFormulas) {
  const auto values =
      waveform({of_area(120.0, kGroundBin - 160.0, 20.0), of_area(80.0, kGroundBin, 6.0)}, 0.0);
  GediL2bSettings settings;
  settings.rhov = 0.5;
  settings.rhog = 0.5;
  settings.omega = 0.7;
  const GediL2bResult r =
      gedi_l2b(input_for(values, 0.0, kGroundBin - 320.0, kGroundBin + 48.0, 0.0), settings);
  EXPECT_NEAR(r.pgap_theta, 1.0 - 120.0 / 200.0, 1e-12);
  EXPECT_NEAR(r.pai, -std::log(0.4) / (0.5 * 0.7), 1e-12);
}

// Chained from L2A as the mission does: the selected group's limits and ground.
TEST(GediL2b, RunsOnL2aSelectedGroup) {
  const auto values =
      waveform({of_area(400.0, kGroundBin - 160.0, 20.0), of_area(200.0, kGroundBin, 6.0)}, 10.0);
  L2aWaveform wave{values, kAxis, 10.0, 0.5};
  const L2aResult l2a = process_l2a(wave);
  ASSERT_GT(l2a.selected_algorithm, 0);
  EXPECT_NEAR(l2a.selected().elev_lowestmode_m, elevation(kGroundBin), 1e-9);
  const GediL2bResult r = gedi_l2b(l2b_input(values, kAxis, 10.0, l2a.selected(), 0.0));
  EXPECT_EQ(r.l2b_quality_flag, 1);
  // a1's thresholds cut the Gaussians' tails about 2 sigma out: Rg within 3 %, cover within 0.02.
  EXPECT_NEAR(r.rg, 200.0, 6.0);
  EXPECT_NEAR(r.cover, 400.0 / (400.0 + 1.5 * 200.0), 0.02);
}

}  // namespace
}  // namespace glaswave
