// `glaswave run`: a track planned, its shots simulated in parallel, products written.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>

#include "pipeline/config/config.hpp"

namespace glaswave {

struct RunRequest {
  std::filesystem::path out_dir;
  int threads = 0;                                    // 0: every core
  std::optional<std::int64_t> first_shot, last_shot;  // --shots A:B, half-open
  std::string command_line;                           // for the products' history
};

struct RunSummary {
  std::int64_t shots = 0;
  std::int64_t shots_flagged = 0;
  std::int64_t ray_queries = 0;
  double wall_s = 0.0;
  std::string vertical_datum;  // what the terrain's heights were measured from, in words
};

// Called after each batch of shots with (shots done, shots in all).
using ProgressCallback = std::function<void(std::int64_t, std::int64_t)>;

// Simulates the shots and writes the products under request.out_dir, which must not exist.
// On failure nothing is left under a product's final name.
RunSummary run_simulation(const Config& config, const RunRequest& request,
                          const ProgressCallback& progress);

}  // namespace glaswave
