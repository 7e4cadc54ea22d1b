// A run abandoned from its progress callback (how Python stops a run on Ctrl-C): the exception
// comes out of run_simulation, and neither a product, nor a .part file, nor the output directory
// is left behind.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "pipeline/engine/run.hpp"
#include "tests/pipeline/engine/engine_test_support.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

namespace fs = std::filesystem;

struct Cancelled {};

TEST(Cancel, AThrowFromTheProgressCallbackLeavesNothingBehind) {
  nlohmann::json document = test_support::plane_shot("glas", 5.0, 0.0, 100);
  document["track"] = {{"type", "pass"},
                       {"start_lat_deg", 0.0},
                       {"start_lon_deg", 0.0},
                       {"shots", 100},
                       {"spacing_m", 10.0}};
  document["output"] = {{"netcdf", true}, {"footprints", true}};
  const Config config = parse_config(document);

  const test_support::ScratchDir scratch("glaswave_cancel_test");
  RunRequest request;
  request.out_dir = scratch / "run";
  request.threads = 1;
  std::int64_t reports = 0;
  const ProgressCallback cancel_after_first = [&](std::int64_t done, std::int64_t total) {
    ++reports;
    EXPECT_LT(done, total);  // stopped before the last batch
    throw Cancelled{};
  };
  EXPECT_THROW(run_simulation(config, request, cancel_after_first), Cancelled);
  EXPECT_EQ(reports, 1);
  EXPECT_FALSE(fs::exists(request.out_dir));
  EXPECT_TRUE(fs::is_empty(scratch.path()));
}

}  // namespace
}  // namespace glaswave
