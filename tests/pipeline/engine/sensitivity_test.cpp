// PHYSICS.md section 7: the seed's sensitivity table (Table 3, 1064 nm). From the base case of
// Tables 1 and 2, one parameter at a time, the changes of TR, CR and GR (partitioned by position
// in the waveform) have the signs the seed reports. Same seed for every case, so the trees and
// the ray streams are the same and the differences are the parameter's.
#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "footprints/track.hpp"
#include "pipeline/engine/inputs.hpp"
#include "tests/pipeline/engine/engine_test_support.hpp"

namespace glaswave {
namespace {

struct Returns {
  double tr = 0, cr = 0, gr = 0;  // mean over the track, 1064 nm
};

Returns simulate(const std::string& key, const nlohmann::json& value) {
  nlohmann::json document = {
      {"seed", 3},
      {"sensor", {{"preset", "north2010"}}},
      {"simulation", {{"rays_per_shot", 4000}}},
      {"terrain", {{"plane", {{"origin_lat_deg", 45.0}, {"origin_lon_deg", 7.0}}}}},
      {"canopy", nlohmann::json::object()},  // Table 1
      {"track",
       {{"type", "pass"},
        {"start_lat_deg", 45.0},
        {"start_lon_deg", 7.0},
        {"shots", 6},
        {"spacing_m", 172.0}}},
  };
  if (!key.empty()) apply_override(document, key + "=" + value.dump());
  const std::vector<ShotRecord> records = test_support::simulate_track(document).records;
  Returns mean;
  for (const ShotRecord& record : records) {
    mean.tr += record.energy_tr_J[1] / records.size();
    mean.cr += record.energy_cr_J[1] / records.size();
    mean.gr += record.energy_gr_J[1] / records.size();
  }
  return mean;
}

TEST(SeedTable3, SignsOfTheChangesAreTheSeeds) {
  const Returns base = simulate("", nullptr);
  ASSERT_GT(base.cr, 0.0);
  ASSERT_GT(base.gr, 0.0);
  auto percent = [&](double value, double reference) { return 100.0 * (value / reference - 1.0); };
  struct Case {
    std::string key;
    nlohmann::json value;
    int tr, cr, gr;  // expected sign of the change; 0: unchanged (within 2 %)
  };
  const Case cases[] = {
      {"canopy.pai", 1.0, -1, -1, +1},
      {"canopy.lad", "planophile", +1, +1, -1},
      {"canopy.lad", "erectophile", -1, -1, +1},
      {"canopy.leaf_reflectance", 0.45, +1, +1, +1},
      {"canopy.leaf_transmittance", 0.45, +1, +1, +1},
      {"terrain.soil_reflectance", 0.2, +1, 0, +1},
  };
  for (const Case& c : cases) {
    const Returns r = simulate(c.key, c.value);
    const std::array<double, 3> change = {percent(r.tr, base.tr), percent(r.cr, base.cr),
                                          percent(r.gr, base.gr)};
    const std::array<int, 3> expected = {c.tr, c.cr, c.gr};
    const char* names[] = {"TR", "CR", "GR"};
    for (int i = 0; i < 3; ++i) {
      const std::string what =
          c.key + "=" + c.value.dump() + " " + names[i] + " " + std::to_string(change[i]) + " %";
      if (expected[i] > 0) {
        EXPECT_GT(change[i], 0.5) << what;
      } else if (expected[i] < 0) {
        EXPECT_LT(change[i], -0.5) << what;
      } else {
        EXPECT_NEAR(change[i], 0.0, 2.0) << what;  // soil leaves CR as it is
      }
    }
    if (c.key == "canopy.pai") {
      // The seed: CR about -51 %, GR about +54 %.
      EXPECT_NEAR(change[1], -51.0, 15.0);
      EXPECT_NEAR(change[2], 54.0, 20.0);
    }
  }
}

}  // namespace
}  // namespace glaswave
