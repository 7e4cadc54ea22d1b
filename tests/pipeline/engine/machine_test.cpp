// The memory a run or `brf` would hold, estimated from the configuration before anything is
// allocated (pipeline/engine/machine.hpp), and refused with the limit in the message at the key
// that makes it large.
#include "pipeline/engine/machine.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>

#include "core/error.hpp"
#include "pipeline/config/config.hpp"
#include "tests/pipeline/config/config_test_support.hpp"

namespace glaswave {
namespace {

using nlohmann::json;
using namespace test_support;  // doc, error_of
using ::testing::HasSubstr;
using ::testing::StartsWith;

// The estimate against the numbers computed here from the same geometry: the glas preset's
// field of view from 600 km, 1.2 times its reach plus 2 m and 100 m of margin for the forest's
// diffuse light, and random crowns at -ln(1 - cover) / (pi r^2) a square metre.
TEST(RunMemory, CountsTheTreesUnderTheFieldOfView) {
  const Config c = parse_config(doc(R"({"sensor": {"preset": "glas"}, "canopy": {}})"));
  const RunMemory m = estimate_run_memory(c);
  const double half_m = 1.2 * 600000.0 * std::tan(0.5 * c.sensor.ifov_rad) + 102.0;
  EXPECT_NEAR(m.scene_half_size_m, half_m, 1e-6);
  const double density = -std::log(1.0 - 0.7) / (std::numbers::pi * 8.0 * 8.0);
  EXPECT_NEAR(m.trees, density * 4.0 * half_m * half_m, 1e-6 * m.trees);
  EXPECT_NEAR(m.bytes, m.threads * (m.trees * 2560.0 + m.waveform_bytes), 1.0);
  EXPECT_GT(m.available_bytes, 0.0);
  EXPECT_NO_THROW(check_run(c));
  // Bare ground has no trees; a layer neither.
  EXPECT_EQ(estimate_run_memory(parse_config(doc("{}"))).trees, 0.0);
  EXPECT_EQ(estimate_run_memory(parse_config(doc(R"({"canopy": {"crown_shape": "layer"}})"))).trees,
            0.0);
}

TEST(RunMemory, BeyondTheMachineIsRefusedAtTheKeyThatMakesIt) {
  // 1 cm crowns: about 1e9 trees a shot, terabytes.
  const Config dense = parse_config(doc(R"({"canopy": {"crown_radius_m": 0.01}})"));
  try {
    check_run(dense);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.place(), "/canopy/crown_radius_m");
    EXPECT_THAT(e.message(), StartsWith("a run would hold about "));
    EXPECT_THAT(e.message(), HasSubstr(" of memory this process may have"));
  }
  // The widest field of view from the highest altitude: a scene 2400 km across.
  const Config wide = parse_config(
      doc(R"({"sensor": {"ifov_rad": 0.05}, "track": {"altitude_m": 4e7}, "canopy": {}})"));
  try {
    check_run(wide);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.place(), "/track/altitude_m");
  }
}

// brf's scene: one for every thread, its tile in whole pixels with 5 m beyond each side over a
// periodic plane, the trees on it at -ln(1 - cover) / (pi r^2) a square metre, and scene.tif's
// bands of 8-byte pixels held twice.
TEST(BrfMemory, CountsTheTreesOfTheTileAndTheImage) {
  const Config c = parse_config(doc(R"({"sensor": {"preset": "glas"}, "canopy": {},
      "brf": {"scene_size_m": 99.5, "image_resolution_m": 2}})"));
  const BrfMemory m = estimate_brf_memory(c);
  EXPECT_EQ(m.pixels, 50.0);
  EXPECT_EQ(m.scene_side_m, 110.0);
  const double density = -std::log(1.0 - 0.7) / (std::numbers::pi * 8.0 * 8.0);
  EXPECT_NEAR(m.trees, density * 110.0 * 110.0, 1e-9 * m.trees);
  EXPECT_NEAR(m.image_bytes, 2.0 * 50 * 50 * 8 * 2, 1e-9);  // glas: 2 bands
  EXPECT_NEAR(m.bytes, m.trees * 2560.0 + m.image_bytes, 1e-6);
  EXPECT_NO_THROW(check_brf(c));
  // Over a DEM the scene reaches 100 m beyond the tile.
  const Config dem = parse_config(doc(R"({"terrain": {"dem": "x.tif"}, "brf": {}})"));
  EXPECT_EQ(estimate_brf_memory(dem).scene_side_m, 500.0);  // the default 300 m tile
}

TEST(BrfMemory, ATileThatCannotBePhysicalOrFitIsRefusedAtItsKey) {
  EXPECT_EQ(error_of(doc(R"({"brf": {"scene_size_m": 20000}})")),
            "/brf/scene_size_m: must be in (0, 10000], got 20000");
  const auto refusal = [](const std::string& text) {
    try {
      check_brf(parse_config(doc(text)));
    } catch (const Error& e) {
      return e.place() + ": " + e.message();
    }
    return std::string("accepted");
  };
  EXPECT_EQ(refusal(R"({"brf": {"scene_size_m": 10000, "image_resolution_m": 0.5}})"),
            "/brf/image_resolution_m: scene.tif would be 20000 pixels across (10000 m at 0.5 m a "
            "pixel); at most 8192");
  EXPECT_EQ(refusal(R"({"brf": {"scene_size_m": 8192, "image_resolution_m": 1}})"), "accepted");
  // 5 cm crowns over the widest tile: 3e10 trees, tens of terabytes.
  EXPECT_THAT(refusal(R"({"canopy": {"crown_radius_m": 0.05, "cover": 0.9},
      "brf": {"scene_size_m": 10000, "image_resolution_m": 10}})"),
              StartsWith("/brf/scene_size_m: brf's scene would hold about "));
  EXPECT_THAT(refusal(R"({"canopy": {"crown_radius_m": 0.01}})"),
              StartsWith("/canopy/crown_radius_m: brf's scene would hold about "));
  // 256 bands of 8192 x 8192 pixels: 256 GiB of image.
  json bands = json::array();
  for (int i = 0; i < 256; ++i)
    bands.push_back({{"name", std::string("b").append(std::to_string(i))},
                     {"wavelength_nm", 500 + i},
                     {"pulse_energy_mJ", 1},
                     {"atmos_transmission_roundtrip", 0.9}});
  const std::string many_bands = json{
      {"sensor", {{"bands", bands}, {"bins", 100}}},
      {"canopy", nullptr},
      {"brf",
       {{"scene_size_m", 8192}}}}.dump();
  EXPECT_THAT(refusal(many_bands),
              StartsWith("/brf/image_resolution_m: brf's scene would hold about 256 GiB"));
}

}  // namespace
}  // namespace glaswave
