// The configuration's limits (issue 13): JSON nesting and duplicate keys refused before anything
// recurses, physical limits declared with the keys (so in the schema too), and the memory a run
// would hold estimated before anything is allocated, refused with the limit in the message.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>

#include "pipeline/config/json_reader.hpp"
#include "pipeline/config/keys.hpp"
#include "tests/pipeline/config/config_test_support.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

using nlohmann::json;
using test_support::doc;
using test_support::error_of;
using ::testing::HasSubstr;
using ::testing::StartsWith;

std::string parse_error(const std::string& text, const std::string& prefix = "") {
  try {
    parse_json_checked(text, prefix);
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::config);
    return e.what();
  }
  return "";
}

TEST(JsonNesting, DeeperThanTheLimitIsRefusedAtItsOutermostKeys) {
  const std::string deep = std::string(100000, '[') + std::string(100000, ']');
  EXPECT_EQ(parse_error("{\"seed\": " + deep + "}"),
            "/seed/0/0/...: nests deeper than 64 levels of objects and arrays");
  EXPECT_EQ(parse_error(deep, "/seed"),
            "/seed/0/0/0/...: nests deeper than 64 levels of objects and arrays");
  // 64 levels are fine, 65 are not.
  const std::string levels_64 = std::string(64, '[') + std::string(64, ']');
  EXPECT_EQ(parse_error(levels_64), "");
  EXPECT_THAT(parse_error("[" + levels_64 + "]"), HasSubstr("nests deeper than 64"));
}

TEST(JsonNesting, ReachesTheFileAndSet) {
  const test_support::ScratchDir dir("glaswave_limits_test");
  const auto file = dir / "deep.json";
  std::ofstream(file) << "{\"canopy\": {\"lad\": " << std::string(1000, '[') << "}";
  try {
    read_json_file(file);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()),
              "/canopy/lad/0/...: nests deeper than 64 levels of objects and arrays (" +
                  file.string() + ")");
  }
  json document = json::object();
  try {
    apply_override(document, "track.points=" + std::string(100000, '[') + "]");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_THAT(std::string(e.what()),
                StartsWith("/track/points/0/0/0/...: nests deeper than 64 levels"));
    EXPECT_THAT(std::string(e.what()), HasSubstr("(from --set track.points)"));
  }
}

// A configuration is a regular file: a FIFO nobody writes is refused before it is opened, which
// would wait for ever.
TEST(ConfigFile, AFifoIsRefusedNotWaitedFor) {
  const test_support::ScratchDir dir("glaswave_limits_test");
  const auto fifo = dir / "config.json";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  try {
    read_json_file(fifo);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()),
              fifo.string() +
                  ": cannot read the configuration: it is a FIFO (a pipe), not a regular file");
  }
}

TEST(JsonDuplicateKeys, AreRefusedWithTheirPath) {
  EXPECT_EQ(parse_error(R"({"seed": 1, "seed": 2})"),
            "/seed: duplicate key: the object gives \"seed\" twice");
  EXPECT_EQ(parse_error(R"({"sensor": {"bands": [{"name": "a"}, {"name": "b", "name": "c"}]}})"),
            "/sensor/bands/1/name: duplicate key: the object gives \"name\" twice");
  // The same key in two objects is no duplicate, nor in objects after an array.
  EXPECT_EQ(parse_error(R"({"a": {"x": 1}, "b": {"x": 2}, "c": [[1, 2], {"x": 3}], "x": 4})"), "");
}

TEST(PhysicalLimits, AreDeclaredWithTheKeysAndInTheSchema) {
  EXPECT_EQ(error_of(doc(R"({"sensor": {"ifov_rad": 3}})")),
            "/sensor/ifov_rad: must be in (0, 0.05], got 3");
  EXPECT_EQ(error_of(doc(R"({"sensor": {"divergence_sigma_rad": 0.1}})")),
            "/sensor/divergence_sigma_rad: must be in (0, 0.05], got 0.1");
  EXPECT_EQ(error_of(doc(R"({"track": {"altitude_m": 1e10}})")),
            "/track/altitude_m: must be in (0, 40000000], got 10000000000.0");
  EXPECT_EQ(error_of(doc(R"({"simulation": {"max_order": 1000000}})")),
            "/simulation/max_order: must be <= 1000, got 1000000");
  EXPECT_THAT(error_of(doc(R"({"track": {"type": "orbit", "semi_major_axis_m": 4e7,
      "eccentricity": 0.5}})")),
              StartsWith("/track/eccentricity: puts the apogee 53621863 m high, above the limit"));
  const json schema = configuration_schema();
  EXPECT_EQ(schema["properties"]["sensor"]["properties"]["ifov_rad"]["maximum"], 0.05);
  EXPECT_EQ(schema["properties"]["track"]["properties"]["altitude_m"]["maximum"], 4.0e7);
  EXPECT_EQ(schema["properties"]["simulation"]["properties"]["rays_per_shot"]["maximum"],
            1000000000);
}

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

// Found by tests/reliability/inputs_tried.py: a NUL byte inside a path cut it where the C
// library read it, and the file before it was read instead. Refused where paths come from JSON.
TEST(PathKeys, ANulByteIsRefusedNotCut) {
  const std::string nul("dem.tif\0.ignored", 16);
  nlohmann::json dem = doc("{}");
  dem["terrain"] = {{"dem", nul}};
  EXPECT_EQ(error_of(dem),
            "/terrain/dem: a path must not hold a NUL byte (at byte 7 of \"dem.tif\\0.ignored\"): "
            "the file before it would be read instead");
  for (const char* key : {"crowns_file", "stands"}) {
    nlohmann::json canopy = doc("{}");
    canopy["canopy"] = {{key, nul}};
    EXPECT_THAT(error_of(canopy),
                StartsWith("/canopy/" + std::string(key) + ": a path must not hold a NUL byte"));
  }
  nlohmann::json ephemeris = doc("{}");
  ephemeris["track"] = {{"type", "ephemeris"}, {"ephemeris", nul}};
  EXPECT_THAT(error_of(ephemeris), StartsWith("/track/ephemeris: a path must not hold a NUL"));
  nlohmann::json granule = doc("{}");
  granule["track"] = {{"type", "granule"}, {"file", nul}};
  EXPECT_THAT(error_of(granule), StartsWith("/track/file: a path must not hold a NUL"));
}

}  // namespace
}  // namespace glaswave
