// output.metrics false: the shot's waveforms, energies and truth are those of a run with the
// metrics, bit for bit (the random streams do not depend on them), and every metric is fill.
#include <gtest/gtest.h>

#include <cmath>

#include "pipeline/engine/machine.hpp"
#include "tests/pipeline/engine/engine_test_support.hpp"

namespace glaswave {
namespace {

using test_support::plane_shot;
using test_support::simulate_track;
using test_support::SimulatedTrack;

TEST(MetricsOff, SameWaveformsAndMetricsLeftFill) {
  nlohmann::json document = plane_shot("north2010", 10.0, 0.0, 300);
  const SimulatedTrack with = simulate_track(document);
  document["output"]["metrics"] = false;
  const SimulatedTrack without = simulate_track(document);
  ASSERT_EQ(with.records.size(), 1u);
  ASSERT_EQ(without.records.size(), 1u);
  const ShotRecord& a = with.records[0];
  const ShotRecord& b = without.records[0];
  EXPECT_EQ(a.rx_waveform_W, b.rx_waveform_W);
  EXPECT_EQ(a.rx_waveform_ground_W, b.rx_waveform_ground_W);
  EXPECT_EQ(a.rx_energy_J, b.rx_energy_J);
  EXPECT_EQ(a.reflectance, b.reflectance);  // noise-free: from rx_energy, not energy_tr
  EXPECT_EQ(a.slope_deg, b.slope_deg);
  EXPECT_EQ(a.footprint_lonlat, b.footprint_lonlat);
  EXPECT_EQ(b.quality_flag, quality_good);
  for (std::size_t band = 0; band < 2; ++band) {
    EXPECT_GE(a.n_peaks[band], 1);
    EXPECT_TRUE(std::isfinite(a.energy_tr_J[band]));
    EXPECT_EQ(b.n_peaks[band], 0);
    EXPECT_TRUE(std::isnan(b.energy_tr_J[band]));
    EXPECT_TRUE(std::isnan(b.ground_elev_est_m[band]));
    ASSERT_EQ(b.rh_m[band].size(), 101u);
    EXPECT_TRUE(std::isnan(b.rh_m[band][50]));
    ASSERT_EQ(b.gauss_amp_W[band].size(), 6u);
    EXPECT_TRUE(std::isnan(b.gauss_amp_W[band][0]));
  }
}

TEST(MetricsOff, PlotsNeedTheMetrics) {
  nlohmann::json document = plane_shot("north2010", 0.0, 0.0, 10);
  document["output"] = {{"metrics", false}, {"plots", true}};
  const Config config = parse_config(document);
  try {
    check_run(config);
    FAIL() << "plots without metrics were accepted";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("/output/metrics"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace glaswave
