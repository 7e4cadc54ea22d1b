// A run killed with SIGKILL leaves no product under its final name, is refused without
// --resume, and with --resume ends with products identical to an uninterrupted run's; a full
// disk ends a run with exit status 4, one line saying so, and nothing left (PRODUCT.md 2).
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "tests/pipeline/app/product_compare.hpp"
#include "tests/pipeline/app/run_control.hpp"
#include "tests/pipeline/engine/engine_test_support.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

namespace fs = std::filesystem;
using namespace test_support;

// A pass over a forest, long enough (many batches on one thread) to be killed half way.
std::string write_config(const fs::path& dir, int shots) {
  const nlohmann::json config = {
      {"seed", 5},
      {"sensor", {{"preset", "glas"}}},
      {"simulation", {{"rays_per_shot", 300}, {"max_order", 2}}},
      {"terrain",
       {{"plane", {{"origin_lat_deg", 46.0}, {"origin_lon_deg", 8.0}, {"slope_deg", 5.0}}}}},
      {"canopy", {{"cover", 0.5}}},
      {"track",
       {{"type", "pass"},
        {"start_lat_deg", 46.0},
        {"start_lon_deg", 8.0},
        {"shots", shots},
        {"spacing_m", 100.0}}},
  };
  const fs::path file = dir / "pass.json";
  std::ofstream(file) << config.dump(2);
  return file.string();
}

class Resume : public ::testing::Test {
 protected:
  // The uninterrupted run, and the size its journal reached (it is removed at the end).
  void SetUp() override {
    config_ = write_config(dir_.path(), 32);
    const fs::path whole = dir_ / "whole";
    const pid_t pid = start_glaswave(run_arguments(whole));
    int status = 0;
    while (waitpid(pid, &status, WNOHANG) != pid) {
      journal_whole_ = std::max(journal_whole_, size_or_zero(whole / "glaswave.journal"));
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    // Half way, in at least its second batch of 8 shots.
    half_ = std::max<std::uintmax_t>(journal_whole_ / 2, 17);
  }
  std::string run_arguments(const fs::path& out) const {
    return "run " + config_ + " --quiet --threads 1 --out " + out.string();
  }

  ScratchDir dir_{"glaswave_resume"};
  std::string config_;
  std::uintmax_t journal_whole_ = 0, half_ = 17;
};

TEST_F(Resume, AKilledRunIsRefusedWithoutResumeAndFinishedIdenticallyWithIt) {
  // Killed at once (nothing made, or only the directory), after its first batch of 8 shots, and
  // about half way.
  const std::uintmax_t journal_bytes[] = {0, 17, half_};
  for (std::size_t round = 0; round < std::size(journal_bytes); ++round) {
    const std::uintmax_t wait_for = journal_bytes[round];
    const fs::path out = dir_ / ("killed" + std::to_string(round));
    const pid_t pid = start_glaswave(run_arguments(out));
    ASSERT_TRUE(kill_when(pid, out / "glaswave.journal", wait_for)) << "the run ended first";
    for (const char* product : {"shots.nc", "footprints.geojson"})
      EXPECT_FALSE(fs::exists(out / product)) << product << " under its final name";
    if (fs::exists(out / "glaswave.journal")) {
      const CommandOutcome refused = run_glaswave(run_arguments(out));
      EXPECT_EQ(refused.status, 2) << refused.output;
      EXPECT_NE(refused.output.find("--resume"), std::string::npos) << refused.output;
      EXPECT_EQ(std::count(refused.output.begin(), refused.output.end(), '\n'), 1);
    }
    const CommandOutcome resumed = run_glaswave(run_arguments(out) + " --resume");
    ASSERT_EQ(resumed.status, 0) << resumed.output;
    EXPECT_FALSE(fs::exists(out / "glaswave.journal"));
    expect_same_products(dir_ / "whole", out);
  }
}

TEST_F(Resume, ATornJournalLosesOnlyItsLastBatch) {
  const fs::path out = dir_ / "torn";
  ASSERT_TRUE(kill_when(start_glaswave(run_arguments(out)), out / "glaswave.journal", half_));
  // A frame cut short, as a kill in the middle of a write leaves it.
  const fs::path journal = out / "glaswave.journal";
  fs::resize_file(journal, fs::file_size(journal) - 100);
  const CommandOutcome resumed = run_glaswave(run_arguments(out) + " --resume");
  ASSERT_EQ(resumed.status, 0) << resumed.output;
  EXPECT_NE(resumed.output.find("kept from the interrupted run"), std::string::npos)
      << resumed.output;
  expect_same_products(dir_ / "whole", out);
}

// A journal in another glaswave version's format (its magic "GWJRNL" and other digits), or a
// file that is not a journal at all, is named and refused, and kept.
TEST_F(Resume, AnotherVersionsJournalOrAnotherFileIsRefused) {
  const fs::path out = dir_ / "version";
  ASSERT_TRUE(kill_when(start_glaswave(run_arguments(out)), out / "glaswave.journal", 17));
  const fs::path journal = out / "glaswave.journal";
  for (const std::string magic : {"GWJRNL02", "PK\x03\x04zip!"}) {
    {
      std::fstream file(journal, std::ios::in | std::ios::out | std::ios::binary);
      file.write(magic.data(), 8);  // little-endian: the name's bytes as they are on disk
    }
    const CommandOutcome refused = run_glaswave(run_arguments(out) + " --resume");
    EXPECT_EQ(refused.status, 2) << refused.output;
    EXPECT_NE(refused.output.find(journal.string()), std::string::npos) << refused.output;
    EXPECT_NE(refused.output.find(magic == "GWJRNL02" ? "another glaswave version"
                                                      : "not a glaswave run journal"),
              std::string::npos)
        << refused.output;
    EXPECT_TRUE(fs::exists(journal));
  }
}

TEST_F(Resume, AnotherConfigurationOrAFinishedRunIsNotResumed) {
  const fs::path out = dir_ / "other";
  ASSERT_TRUE(kill_when(start_glaswave(run_arguments(out)), out / "glaswave.journal", 17));
  for (const char* change : {" --set canopy.pai=2", " --seed 6", " --shots 0:20"}) {
    const CommandOutcome refused = run_glaswave(run_arguments(out) + " --resume" + change);
    EXPECT_EQ(refused.status, 2) << change << ": " << refused.output;
    EXPECT_NE(refused.output.find("another configuration"), std::string::npos) << refused.output;
  }
  EXPECT_TRUE(fs::exists(out / "glaswave.journal"));  // refused, kept for the right command
  // A finished run has nothing to resume.
  const CommandOutcome finished = run_glaswave(run_arguments(dir_ / "whole") + " --resume");
  EXPECT_EQ(finished.status, 2);
  EXPECT_NE(finished.output.find("no interrupted run"), std::string::npos) << finished.output;
  // --resume where there is no directory runs from the beginning.
  const CommandOutcome fresh = run_glaswave(run_arguments(dir_ / "fresh") + " --resume");
  ASSERT_EQ(fresh.status, 0) << fresh.output;
  expect_same_products(dir_ / "whole", dir_ / "fresh");
}

// A small file system the test makes: tmpfs in a mount namespace of its own (root, or a user
// namespace), else a file size limit (ulimit -f, which fails writes with EFBIG as a full disk
// fails them with ENOSPC). At every size the run ends with status 4, one line naming the file
// and saying the disk is full, and nothing under the output directory.
TEST(FullDisk, EndsTheRunWithStatus4OneLineAndNothingLeft) {
  const ScratchDir dir("glaswave_full_disk");
  const std::string config = write_config(dir.path(), 20);
  const fs::path mount = dir / "small";
  fs::create_directories(mount);
  const bool namespaces = std::system(("unshare -rm sh -c 'mount -t tmpfs -o size=64k none " +
                                       mount.string() + "' >/dev/null 2>&1")
                                          .c_str()) == 0;
  const std::vector<std::string> limits =
      namespaces ? std::vector<std::string>{"32k", "96k", "160k", "256k"}
                 : std::vector<std::string>{"30", "90", "150", "250"};
  for (const std::string& limit : limits) {
    const fs::path out = mount / "out";
    const std::string run = std::string(GLASWAVE_BINARY) + " run " + config +
                            " --quiet --threads 1 --out " + out.string();
    // The status and what is left are printed inside, where the small file system is seen.
    const std::string script = run + " 2>&1; echo \"status=$?\"; ls -A " + out.string() +
                               " 2>/dev/null | while read -r f; do echo \"left: $f\"; done";
    const std::string command = namespaces ? "unshare -rm sh -c 'mount -t tmpfs -o size=" + limit +
                                                 " none " + mount.string() + " && " + script + "'"
                                           : "sh -c 'ulimit -f " + limit + "; " + script + "'";
    FILE* pipe = popen(command.c_str(), "r");
    std::string output;
    std::array<char, 4096> buffer;
    while (std::fgets(buffer.data(), buffer.size(), pipe)) output += buffer.data();
    pclose(pipe);
    SCOPED_TRACE(limit + (namespaces ? " tmpfs" : " KiB file size limit") + ": " + output);
    EXPECT_NE(output.find("status=4\n"), std::string::npos);
    EXPECT_EQ(output.find("left: "), std::string::npos);
    EXPECT_EQ(output.rfind("glaswave: error: " + out.string() + "/", 0), 0u);
    EXPECT_NE(output.find("the disk is full"), std::string::npos);
    EXPECT_EQ(std::count(output.begin(), output.end(), '\n'), 2);  // the error and the status
    fs::remove_all(out);  // what a file size limit's run might have left (it must leave none)
  }
}

// Found by tests/reliability/inputs_tried.py: two runs on one --out (two fresh runs, or two
// --resume of one killed run) started together removed and wrote each other's files and both
// failed half-way with exit status 4. The first holds the directory's lock; the second is refused
// at once, with exit status 2, saying so, and leaves the first's files alone.
TEST(OutputLock, ASecondRunOnTheSameOutIsRefusedAtOnce) {
  const ScratchDir dir("glaswave_output_lock");
  const std::string config = write_config(dir.path(), 400);  // long enough to be caught running
  const fs::path out = dir / "out";
  const std::string arguments = "run " + config + " --quiet --threads 1 --out " + out.string();
  const auto wait_for_holder = [&](pid_t pid) {
    // The holder writes its process id into the lock file once it holds it.
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (std::chrono::steady_clock::now() < deadline) {
      std::ifstream lock(out / ".glaswave.lock");
      std::string holder;
      if (lock >> holder && holder == std::to_string(pid)) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return false;
  };
  const auto expect_refused = [&](const std::string& command, pid_t holder) {
    const CommandOutcome refused = run_glaswave(command);
    EXPECT_EQ(refused.status, 2) << refused.output;
    EXPECT_EQ(refused.output, "glaswave: error: " + out.string() +
                                  ": another glaswave run is writing into this output directory "
                                  "(process " +
                                  std::to_string(holder) +
                                  "): wait for it to end, or choose another --out\n");
  };
  // Two fresh runs.
  const pid_t first = start_glaswave(arguments);
  ASSERT_TRUE(wait_for_holder(first));
  expect_refused(arguments, first);
  ASSERT_TRUE(kill_when(first, out / "glaswave.journal", 17));
  // Two --resume of the killed run: the stale lock file of the killed run does not block the
  // first, which holds the directory; the second is refused.
  const pid_t resumed = start_glaswave(arguments + " --resume");
  ASSERT_TRUE(wait_for_holder(resumed));
  expect_refused(arguments + " --resume", resumed);
  EXPECT_TRUE(fs::exists(out / "glaswave.journal"));
  kill(resumed, SIGTERM);
  int status = 0;
  waitpid(resumed, &status, 0);
}

}  // namespace
}  // namespace glaswave
