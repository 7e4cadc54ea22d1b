// The configuration's limits (issue 13): JSON nesting and duplicate keys refused before anything
// recurses, and physical limits declared with the keys (so in the schema too). The memory a run
// would hold is the engine's (tests/pipeline/engine/machine_test.cpp).
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <time.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
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

// An object of 65 537 objects (issue 42: facets' materials) parses in time linear in its members:
// nlohmann-json's callback parser walked the parent at the end of each child, 30 s for it. 16
// times the members take 16 times as long, not 256: at most 64 times, the best of three each, in
// the thread's CPU time (wall time on a loaded machine measured the load, not the parse).
TEST(JsonMembers, AnObjectOfObjectsParsesInTimeLinearInItsMembers) {
  const auto text = [](int members) {
    std::string t = "{\"materials\": {";
    for (int i = 0; i < members; ++i)
      t += (i ? ", \"m" : "\"m") + std::to_string(i) + "\": {\"reflectance\": 0.3}";
    return t + "}}";
  };
  const auto thread_cpu_s = [] {
    timespec now{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
    return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
  };
  const auto seconds = [&](const std::string& t) {
    double best = 1e9;
    for (int round = 0; round < 3; ++round) {
      const double start = thread_cpu_s();
      parse_json_checked(t);
      best = std::min(best, thread_cpu_s() - start);
    }
    return best;
  };
  const std::string small = text(4097), large = text(65537);
  EXPECT_EQ(parse_json_checked(small), json::parse(small));
  const double ratio = seconds(large) / seconds(small);
  EXPECT_LT(ratio, 64.0);
  // The messages of the pass before the parse, in the order the text gives them.
  EXPECT_EQ(parse_error(R"({"a": [1, 2, {"b": 1, "b": 2}]})"),
            "/a/2/b: duplicate key: the object gives \"b\" twice");
  EXPECT_THROW(parse_json_checked(R"({"a": [1, {"b": }], "a": 1})"), json::parse_error);
  EXPECT_THROW(parse_json_checked(R"({"a": 1e400})"), json::out_of_range);
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
