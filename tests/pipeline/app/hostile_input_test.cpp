// Hostile and careless input end to end (issue 13): each ends `check` and `run` alike with its
// exit status and one line naming the key or the file, no product, no escape code, and nothing
// of a file of another kind echoed; and a run whose stderr is not a terminal reports its
// progress as plain lines.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tests/pipeline/engine/engine_test_support.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using namespace test_support;

// Under AddressSanitizer (./scripts/test --sanitize) the voxel grid's reader program, sanitized
// too, reports HDF5 1.10.8's own overread of a corrupt global heap (H5HG_read, inside libhdf5:
// tests/fuzz/known/README.md) on the standard error it shares with glaswave, before it ends and
// glaswave refuses the grid; a release build's reader ends of it without a word. That report, and
// no other, is taken off the start of the output.
std::string without_readers_hdf5_report(std::string output) {
#if defined(__SANITIZE_ADDRESS__)
  const std::string end = "==ABORTING\n";
  for (std::size_t at = output.find(end);
       output.rfind("=====", 0) == 0 && at != std::string::npos &&
       output.substr(0, at).find(" in H5HG_read ") != std::string::npos;
       at = output.find(end))
    output.erase(0, at + end.size());
#endif
  return output;
}

class HostileInput : public ::testing::Test {
 protected:
  json base() const { return one_glas_shot(); }
  std::string write(const std::string& name, const std::string& text) {
    const fs::path file = dir_ / name;
    std::ofstream(file) << text;
    return file.string();
  }
  std::string write_config(const json& changes) {
    json config = base();
    config.merge_patch(changes);
    return write("config.json", config.dump(2));
  }
  // A stands file of one square feature about the track's start, with `properties`, its
  // corners shifted by `lon_shift_deg`.
  std::string write_stand(const json& properties, double lon_shift_deg = 0.0) {
    const double w = 7.99 + lon_shift_deg, e = 8.01 + lon_shift_deg;
    const json feature = {
        {"type", "Feature"},
        {"properties", properties},
        {"geometry",
         {{"type", "Polygon"},
          {"coordinates", {{{w, 45.99}, {e, 45.99}, {e, 46.01}, {w, 46.01}, {w, 45.99}}}}}}};
    return write("stands.geojson",
                 json{{"type", "FeatureCollection"}, {"features", {feature}}}.dump());
  }

  // check and run of `config` (with `options`) end alike: `status`, one line that starts with
  // "glaswave: error: " + `message`, no escape code, and no output directory.
  void expect_refused(const std::string& config, const std::string& options, int status,
                      const std::string& message) {
    const CommandOutcome check = run_glaswave("check " + config + " " + options);
    const CommandOutcome run =
        run_glaswave("run " + config + " --quiet --out " + out().string() + " " + options);
    for (CommandOutcome outcome : {check, run}) {
      outcome.output = without_readers_hdf5_report(outcome.output);
      EXPECT_EQ(outcome.status, status) << message << ": " << outcome.output;
      EXPECT_EQ(outcome.output.rfind("glaswave: error: " + message, 0), 0u) << outcome.output;
      EXPECT_EQ(std::count(outcome.output.begin(), outcome.output.end(), '\n'), 1)
          << outcome.output;
      EXPECT_EQ(outcome.output.find('\x1b'), std::string::npos) << outcome.output;
    }
    EXPECT_FALSE(fs::exists(out())) << message;
  }
  fs::path out() const { return dir_ / "out"; }

  ScratchDir dir_{"glaswave_hostile"};
};

// Issue 42: voxel grids fuzzing found, which crashed the process (HDF5 1.10.8 reading 16 MB past a
// heap buffer on a corrupt NetCDF-4 grid), asked nc_open for 9 GB (a 23-byte classic NetCDF
// declaring 1.1e9 dimensions) or held it for ever (HDF5 spinning on a corrupt NetCDF-4 grid, its
// reader ended at its CPU budget): check and run refuse each with one line naming the file, exit 3.
TEST_F(HostileInput, CorruptVoxelGridsAreRefusedNamingTheFile) {
  for (const std::string name :
       {"regression-netcdf4-hdf5-global-heap", "regression-netcdf3-declares-9-gb",
        "regression-netcdf4-hdf5-spins"}) {
    // The fuzz input's first byte picks the format; the rest is the file.
    std::ifstream in(fs::path(GLASWAVE_SOURCE_DIR) / "tests/fuzz/corpus/voxel" / name,
                     std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ASSERT_GT(bytes.size(), 1u) << name;
    const std::string grid = write(name + ".nc", bytes.substr(1));
    json config = base();
    config["canopy"] = {{"voxels", {{"file", grid}}}};
    expect_refused(write("config.json", config.dump(2)), "", 3, grid + ": ");
  }
}

// Item 3: run sizes that cannot be physical or would not fit in memory, refused by check and
// run before anything is allocated, the limit in the message.
TEST_F(HostileInput, RunSizesBeyondTheLimitsAreRefusedByCheckAndRun) {
  expect_refused(write_config({{"sensor", {{"bins", 100000000}}}}), "", 2,
                 "/sensor/bins: must be <= 16777216, got 100000000");
  expect_refused(write_config({{"sensor", {{"ifov_rad", 3}}}}), "", 2,
                 "/sensor/ifov_rad: must be in (0, 0.05], got 3");
  expect_refused(write_config({{"track", {{"altitude_m", 1e10}}}}), "", 2,
                 "/track/altitude_m: must be in (0, 40000000]");
  expect_refused(write_config({{"simulation", {{"rays_per_shot", 1000000000000}}}}), "", 2,
                 "/simulation/rays_per_shot: must be <= 1000000000, got 1000000000000");
  // A forest of 1 cm crowns under the glas footprint: about 1e9 trees a shot.
  expect_refused(write_config({{"canopy", {{"crown_radius_m", 0.01}}}}), "", 2,
                 "/canopy/crown_radius_m: a run would hold about");
  expect_refused(write_config({{"output", {{"netcdf", false}, {"footprints", false}}}}), "", 2,
                 "/output: nothing to write");
}

// The same for `glaswave brf`'s scene: a tile that cannot be physical, an image too wide, a scene
// beyond the machine's memory; refused by check and brf alike, nothing written.
TEST_F(HostileInput, BrfScenesBeyondTheLimitsAreRefusedByCheckAndBrf) {
  const auto expect_brf_refused = [&](const json& changes, const std::string& message) {
    const std::string config = write_config(changes);
    const CommandOutcome check = run_glaswave("check " + config);
    const CommandOutcome brf = run_glaswave("brf " + config + " --quiet --out " + out().string());
    for (const CommandOutcome& outcome : {check, brf}) {
      EXPECT_EQ(outcome.status, 2) << message << ": " << outcome.output;
      EXPECT_EQ(outcome.output.rfind("glaswave: error: " + message, 0), 0u) << outcome.output;
      EXPECT_EQ(std::count(outcome.output.begin(), outcome.output.end(), '\n'), 1)
          << outcome.output;
    }
    EXPECT_FALSE(fs::exists(out())) << message;
  };
  expect_brf_refused({{"brf", {{"scene_size_m", 1e9}}}},
                     "/brf/scene_size_m: must be in (0, 10000], got 1000000000");
  expect_brf_refused({{"brf", {{"scene_size_m", 10000}, {"image_resolution_m", 0.01}}}},
                     "/brf/image_resolution_m: scene.tif would be 1000000 pixels across");
  // 1 m crowns: a run's scene holds about 0.2 million trees (0.4 GiB a thread), a 10 km tile
  // 74 million (175 GiB).
  expect_brf_refused({{"canopy", {{"crown_radius_m", 1.0}, {"cover", 0.9}}},
                      {"brf", {{"scene_size_m", 10000}, {"image_resolution_m", 10}}}},
                     "/brf/scene_size_m: brf's scene would hold about ");
  expect_brf_refused({{"brf", {{"photons", 1000000000000LL}}}},
                     "/brf/photons: must be <= 1000000000, got 1000000000000");
}

// Item 8: roughness too fine to mesh under the beam even at one node per correlation length is
// refused by run when its first shot builds the ground, and by check, which builds that shot's
// scene for it.
TEST_F(HostileInput, RoughnessTooFineForTheBeamIsRefusedByCheckAndRun) {
  expect_refused(
      write_config({{"terrain", {{"roughness", {{"rms_m", 0.45}, {"correlation_m", 0.05}}}}}}), "",
      2, "/terrain/roughness/correlation_m: 0.05 m is too short to mesh under this beam");
}

// Item 5: a value nested 100 000 levels deep under a known key, in the file or from --set.
TEST_F(HostileInput, DeepNestingIsRefusedBeforeAnythingRecurses) {
  const std::string deep = std::string(100000, '[') + std::string(100000, ']');
  for (const char* key : {"seed", "canopy"}) {
    const std::string config = write("deep.json", "{\"" + std::string(key) + "\": " + deep + "}");
    expect_refused(config, "", 2,
                   std::string("/").append(key).append("/0/0/...: nests deeper than 64 levels"));
  }
  const std::string points =
      write("points.json", "{\"track\": {\"type\": \"points\", \"points\": " + deep + "}}");
  expect_refused(points, "", 2, "/track/points/0/...: nests deeper than 64 levels");
  // The command line has a limit of its own (128 KiB an argument): 60 000 levels.
  const std::string set_deep = std::string(60000, '[') + std::string(60000, ']');
  expect_refused(write_config(json::object()), "--set seed=" + set_deep, 2,
                 "/seed/0/0/0/...: nests deeper than 64 levels");
}

// Item 7: the rest of the list, one by one.
TEST_F(HostileInput, EachItemOfTheListGetsAClearError) {
  expect_refused(write("dup.json", R"({"seed": 1, "canopy": {"pai": 1, "pai": 2}})"), "", 2,
                 "/canopy/pai: duplicate key");
  expect_refused(write_config({{"track",
                                {{"type", "points"},
                                 {"shots", nullptr},
                                 {"points", {{{"lat_deg", 46}, {"lon_deg", 8}, {"name", "a"}}}}}}}),
                 "", 2, "/track/points/0/name: unknown key \"name\"");
  for (const char* key : {"crowns_file", "stands"}) {
    const std::string stands = write_stand({{key, "other"}});
    expect_refused(write_config({{"canopy", {{"stands", stands}}}}), "", 3,
                   stands + ": feature 0: property " + key + " cannot be set by a stand");
  }
  const std::string far = write_stand({{"pai", 1}}, 492.0);
  expect_refused(write_config({{"canopy", {{"stands", far}}}}), "", 3,
                 far + ": feature 0: a position is not on the Earth (longitude 499.99");
  const std::string crowns =
      write("crowns.csv", "x,y,base_m,radius_m,half_height_m\n1e308,0,10,5,5\n");
  expect_refused(write_config({{"canopy", {{"crowns_file", crowns}}}}), "", 3,
                 crowns + ":2: x must be within 1000000 m of the plane's origin");
  expect_refused(write_config({{"canopy", {{"crowns_file", "/dev/zero"}}}}), "", 3,
                 "/dev/zero: cannot read the crowns file: it is a device, not a regular file");
  // A number in JSON is decimal: 0x10 is malformed JSON, from a file; a string from --set.
  const std::string hex = write("hex.json", R"({"seed": 0x10})");
  expect_refused(hex, "", 2, hex + ": malformed JSON at line 1");
  expect_refused(write_config(json::object()), "--set seed=0x10", 2,
                 "/seed: must be an integer, got \"0x10\"");
  // An escape code in a key reaches stderr written out, not raw.
  expect_refused(write_config({{"canopy", {{"p\x1b[31mai", 1}}}}), "", 2,
                 "/canopy/p\\x1b[31mai: unknown key");
}

// Found by tests/reliability/inputs_tried.py: a FIFO nobody writes, given as the configuration or
// as a file it names, is refused at once, not waited for; a stands file without a feature is
// refused (it would change nothing, silently); a crowns file from a spreadsheet (a UTF-8 byte
// order mark, CRLF) is read.
TEST_F(HostileInput, FifosAndEmptyStandsAreRefusedAndSpreadsheetCsvIsRead) {
  const fs::path fifo = dir_ / "fifo";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  expect_refused(
      fifo.string(), "", 2,
      fifo.string() + ": cannot read the configuration: it is a FIFO (a pipe), not a regular file");
  expect_refused(
      write_config({{"canopy", {{"stands", fifo.string()}}}}), "", 3,
      fifo.string() + ": cannot read the stands file: it is a FIFO (a pipe), not a regular file");
  expect_refused(
      write_config({{"canopy", {{"crowns_file", fifo.string()}}}}), "", 3,
      fifo.string() + ": cannot read the crowns file: it is a FIFO (a pipe), not a regular file");
  expect_refused(
      write_config({{"terrain", {{"plane", nullptr}, {"dem", fifo.string()}}}}), "", 3,
      fifo.string() + ": cannot read the DEM: it is a FIFO (a pipe), not a regular file");
  const std::string empty =
      write("empty.geojson", R"({"type": "FeatureCollection", "features": []})");
  expect_refused(write_config({{"canopy", {{"stands", empty}}}}), "", 3,
                 empty + ": holds no feature: no stand to place");
  const std::string crowns =
      write("excel.csv", "\xEF\xBB\xBFx,y,base_m,radius_m,half_height_m\r\n0,0,5,3,3\r\n");
  const CommandOutcome check =
      run_glaswave("check " + write_config({{"canopy", {{"crowns_file", crowns}}}}));
  EXPECT_EQ(check.status, 0) << check.output;
}

// Item 4: the ephemeris error names the file, line and what was expected, never the content of
// a file of another kind (here a password-hash line).
TEST_F(HostileInput, AFileOfAnotherKindIsNeverEchoed) {
  const std::string secret = "root:$6$Zm9vYmFyYmF6$c2VjcmV0aGFzaHZhbHVl:19000:0:99999:7:::";
  const std::string shadow = write("shadow", secret + "\n");
  const std::string config = write_config({{"track",
                                            {{"type", "ephemeris"},
                                             {"ephemeris", shadow},
                                             {"start_lat_deg", nullptr},
                                             {"start_lon_deg", nullptr}}}});
  expect_refused(config, "", 3, shadow + ":1: column 1 is not a column name");
  const CommandOutcome check = run_glaswave("check " + config);
  EXPECT_EQ(check.output.find("Zm9v"), std::string::npos) << check.output;
  EXPECT_EQ(check.output.find("root"), std::string::npos) << check.output;
  // Read as a configuration: the JSON error quotes a few characters at most.
  const CommandOutcome as_json = run_glaswave("check " + shadow);
  EXPECT_EQ(as_json.status, 2) << as_json.output;
  EXPECT_EQ(as_json.output.find("Zm9v"), std::string::npos) << as_json.output;
}

// Item 7's command line: numbers are decimal and in range, and empty values are refused.
TEST_F(HostileInput, CommandLineValuesAreCheckedNotDefaulted) {
  const std::string config = write_config(json::object());
  struct Case {
    std::string options, message;
  };
  const std::vector<Case> cases = {
      {"--seed 18446744073709551616",
       "--seed: is too large: must be <= 18446744073709551615, got 18446744073709551616"},
      {"--seed 0x10", "--seed: must be an integer in [0, 18446744073709551615], got \"0x10\""},
      {"--seed -1", "--seed: must be an integer in [0, 18446744073709551615], got \"-1\""},
      {"--threads 0x10", "--threads: must be an integer in [0, 65536], got \"0x10\""},
      {"--seed \"\"", "--seed: must not be empty"},
      {"--shots \"\"", "--shots: must not be empty"},
      {"--shots 0x1:2", "--shots: expected A:B"},
  };
  for (const Case& c : cases) {
    const CommandOutcome run =
        run_glaswave("run " + config + " --quiet --out " + out().string() + " " + c.options);
    EXPECT_EQ(run.status, 2) << c.options << ": " << run.output;
    EXPECT_EQ(run.output.rfind("glaswave: error: " + c.message, 0), 0u) << run.output;
    EXPECT_EQ(std::count(run.output.begin(), run.output.end(), '\n'), 1) << run.output;
    EXPECT_FALSE(fs::exists(out())) << c.options;
  }
  // --out "" is not "out/config".
  const fs::path here = fs::current_path();
  fs::current_path(dir_.path());
  const CommandOutcome run = run_glaswave("run " + config + " --quiet --out \"\"");
  fs::current_path(here);
  EXPECT_EQ(run.status, 2) << run.output;
  EXPECT_EQ(run.output, "glaswave: error: --out: must not be empty\n");
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

// Progress on a stderr that is not a terminal: plain lines (shots done/total, shots/s, time
// left), no carriage return, no escape code.
TEST_F(HostileInput, ProgressOnANonTerminalIsPlainLines) {
  const std::string config = write_config({{"track", {{"shots", 24}}}});
  const CommandOutcome run =
      run_glaswave("run " + config + " --threads 1 --progress-interval 0 --out " + out().string());
  ASSERT_EQ(run.status, 0) << run.output;
  EXPECT_EQ(run.output.find('\r'), std::string::npos) << run.output;
  EXPECT_EQ(run.output.find('\x1b'), std::string::npos) << run.output;
  // Batches of 8 shots on one thread: after 8 and 16 of 24.
  EXPECT_NE(run.output.find("glaswave: 8/24 shots, "), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("glaswave: 16/24 shots, "), std::string::npos) << run.output;
  EXPECT_NE(run.output.find(" shots/s, "), std::string::npos) << run.output;
  EXPECT_NE(run.output.find(" s left\n"), std::string::npos) << run.output;
}

// A plot script that fails with a traceback after complete products (issue 28): the run keeps
// exit 0 and warns in one line, the traceback in plots.log, the products whole.
TEST_F(HostileInput, APlotErrorIsAWarningAndItsDetailALogFile) {
  const fs::path share = dir_ / "share";
  fs::create_directories(share / "plots");
  std::ofstream(share / "plots" / "plot_products.py")
      << "import sys\nprint('Traceback (most recent call last):', file=sys.stderr)\n"
         "print('  File \"x.py\", line 1', file=sys.stderr)\n"
         "print('ValueError: no plot today', file=sys.stderr)\nsys.exit(1)\n";
  const std::string config = write_config({{"output", {{"plots", true}}}});
  const std::string command = "GLASWAVE_SHARE=" + share.string() + " " +
                              std::string(GLASWAVE_BINARY) + " run " + config + " --quiet --out " +
                              out().string() + " 2>&1 >/dev/null";
  FILE* pipe = popen(command.c_str(), "r");
  std::string output;
  char buffer[4096];
  while (std::fgets(buffer, sizeof buffer, pipe)) output += buffer;
  const int status = pclose(pipe);
  EXPECT_EQ(WEXITSTATUS(status), 0) << output;
  EXPECT_EQ(std::count(output.begin(), output.end(), '\n'), 1) << output;
  EXPECT_EQ(output.rfind("glaswave: warning: plots: plot_products.py exited with status 1: "
                         "ValueError: no plot today",
                         0),
            0u)
      << output;
  EXPECT_TRUE(fs::is_regular_file(out() / "shots.nc")) << output;
  EXPECT_TRUE(fs::is_regular_file(out() / "footprints.geojson")) << output;
  EXPECT_NE(output.find((out() / "plots.log").string()), std::string::npos) << output;
  std::ifstream log(out() / "plots.log");
  const std::string text((std::istreambuf_iterator<char>(log)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("Traceback"), std::string::npos) << text;
}

}  // namespace
}  // namespace glaswave
