// RAMI-IV's lidar measurements out of a `glaswave run` (docs/guide/rami.md): each shot's return,
// binned by height from the ground up and normalised as an apparent reflectance, averaged over the
// run's shots and written in ROMC's format, `DIR/rami/<MES>_<MOD>-<EXP>.mes`.
#pragma once

#include <filesystem>
#include <memory>

#include "pipeline/config/config.hpp"
#include "pipeline/products/product_writer.hpp"

namespace glaswave {

// The writer of config.output.rami (which must be set): it holds each band's sums and writes its
// files when the run finishes, each through an atomic file, so an interrupted run leaves none.
std::unique_ptr<ProductWriter> make_rami_lidar_writer(const std::filesystem::path& out_dir,
                                                      const Config& config, const RunInfo& info);

}  // namespace glaswave
