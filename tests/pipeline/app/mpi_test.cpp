// mpirun -np 2 glaswave run: the shots shared between two processes, products identical in
// every bit to one process's (PRODUCT.md 2); an error is reported once and ends both.
#include <gtest/gtest.h>
#include <unistd.h>

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

class Mpi : public ::testing::Test {
 protected:
  void SetUp() override {
    if (std::system("command -v mpirun >/dev/null 2>&1") != 0)
      GTEST_FAIL() << "no mpirun (scripts/setup installs openmpi-bin)";
    // A forest on rough ground with per-order output: every field a record has, 21 shots so
    // that the last batch is cut short.
    const nlohmann::json config = {
        {"seed", 7},
        {"sensor", {{"preset", "glas"}}},
        {"simulation", {{"rays_per_shot", 300}, {"max_order", 3}}},
        {"terrain",
         {{"plane", {{"origin_lat_deg", -20.0}, {"origin_lon_deg", 30.0}, {"slope_deg", 10.0}}},
          {"roughness", {{"rms_m", 0.3}, {"correlation_m", 3.0}}}}},
        {"canopy", {{"cover", 0.5}}},
        {"track",
         {{"type", "pass"},
          {"start_lat_deg", -20.0},
          {"start_lon_deg", 30.0},
          {"shots", 21},
          {"spacing_m", 100.0}}},
        {"output", {{"per_order", true}}},
    };
    config_ = (dir_ / "pass.json").string();
    std::ofstream(config_) << config.dump(2);
  }

  ScratchDir dir_{"glaswave_mpi"};
  std::string config_;
};

TEST_F(Mpi, TwoProcessesWriteTheProductsOfOne) {
  const CommandOutcome one =
      run_glaswave("run " + config_ + " --quiet --threads 1 --out " + (dir_ / "one").string());
  ASSERT_EQ(one.status, 0) << one.output;
  const CommandOutcome two =
      run_mpi(2, "run " + config_ + " --quiet --threads 1 --out " + (dir_ / "two").string());
  ASSERT_EQ(two.status, 0) << two.output;
  // Rank 0 alone reports: one summary line.
  EXPECT_EQ(std::count(two.output.begin(), two.output.end(), '\n'), 1) << two.output;
  EXPECT_NE(two.output.find("21 shots in"), std::string::npos) << two.output;
  expect_same_products(dir_ / "one", dir_ / "two");
}

TEST_F(Mpi, AnErrorIsReportedOnceAndEndsEveryProcess) {
  const CommandOutcome bad = run_mpi(
      2, "run " + config_ + " --quiet --set canopy.pai=-1 --out " + (dir_ / "bad").string());
  EXPECT_EQ(bad.status, 2) << bad.output;
  EXPECT_EQ(bad.output, "glaswave: error: /canopy/pai: must be >= 0, got -1\n");
  EXPECT_FALSE(fs::exists(dir_ / "bad"));
  // An existing output directory is found by rank 0 alone: every process still ends.
  fs::create_directories(dir_ / "taken");
  const CommandOutcome taken =
      run_mpi(2, "run " + config_ + " --quiet --out " + (dir_ / "taken").string());
  EXPECT_EQ(taken.status, 2) << taken.output;
  EXPECT_EQ(std::count(taken.output.begin(), taken.output.end(), '\n'), 1) << taken.output;
  EXPECT_NE(taken.output.find("output directory exists"), std::string::npos) << taken.output;
}

// mpirun binds a process to one core when it starts two or fewer. A process alone on a machine of
// several cores then runs one thread, not the machine's cores that --threads 0 means, and the run
// says so; unbound, it runs them all and says nothing.
TEST_F(Mpi, AProcessBoundToFewerCoresThanItsShareIsNamed) {
  if (std::thread::hardware_concurrency() < 2) GTEST_SKIP() << "one core: nothing to fall short of";
  const std::string run = "run " + config_ + " --quiet --threads 0 --shots 0:2 --out ";
  const CommandOutcome bound = run_mpi(1, run + (dir_ / "bound").string(), "--bind-to core");
  ASSERT_EQ(bound.status, 0) << bound.output;
  // Alone on the machine, its share is every core.
  const std::string cores = std::to_string(std::thread::hardware_concurrency());
  EXPECT_NE(bound.output.find("glaswave: warning: --threads 0: this process may run on 1 of the "
                              "machine's " +
                              cores + " cores, so it runs 1 thread where " + cores + " were meant"),
            std::string::npos)
      << bound.output;
  EXPECT_NE(bound.output.find("give mpirun --bind-to none"), std::string::npos) << bound.output;
  const CommandOutcome unbound = run_mpi(1, run + (dir_ / "unbound").string(), "--bind-to none");
  ASSERT_EQ(unbound.status, 0) << unbound.output;
  EXPECT_EQ(unbound.output.find("warning"), std::string::npos) << unbound.output;
}

}  // namespace
}  // namespace glaswave
