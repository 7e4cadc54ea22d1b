// `glaswave brf`: FLIGHT's solar mode over the scene around the track's first footprint (a
// periodic tile over a synthetic plane). Per band the albedo and each view's BRF with its
// standard error go to brf.json, the nadir reflectance image to scene.tif (GeoTIFF).
#pragma once

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "pipeline/config/config.hpp"
#include "pipeline/engine/run.hpp"

namespace glaswave {

struct BrfRequest {
  std::filesystem::path out_dir;  // refused when it exists; empty: write nothing
  int threads = 0;                // 0: every core
};

struct BrfSummary {
  nlohmann::json document;  // what brf.json holds
  std::int64_t photons = 0;
  std::int64_t ray_queries = 0;
  double wall_s = 0.0;
  std::string crs;  // of scene.tif
};

// Traces the photons and writes brf.json and scene.tif under request.out_dir. The result is the
// same bits for any thread count. On failure nothing is left under a product's final name.
BrfSummary run_brf(const Config& config, const BrfRequest& request,
                   const ProgressCallback& progress);

}  // namespace glaswave
