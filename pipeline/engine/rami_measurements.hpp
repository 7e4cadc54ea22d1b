// RAMI's measurements out of a `glaswave brf` run (PRODUCT.md section 13): the views RAMI asks
// for, and the files ROMC (the RAMI On-line Model Checker) takes, `<MES>_<MOD>-<EXP>.mes`.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "pipeline/config/config.hpp"
#include "pipeline/shot/brf_shot.hpp"

namespace glaswave {

// Refuses measurements ROMC does not name, a model name ROMC would refuse, an experiment without
// `{band}` when there are several bands (their files would share names).
void check_rami_request(const BrfRamiSettings& rami, std::size_t bands);

// The views brfpp and brfop need, in their files' row order: in the principal plane, view
// zeniths 75, 73, ..., 1 deg toward the sun (relative azimuth SAA - VAA = 0), then 1, ..., 75
// away from it (pi); in the orthogonal plane the same at SAA - VAA = pi/2 then 3 pi/2. 152 views
// when both planes are asked for, none for neither.
std::vector<BrfView> rami_views(const BrfSettings& brf);

// Writes each measurement's file under dir (made here). The result's views are the
// configuration's brf.views followed by rami_views(brf), from first_rami_view on.
void write_rami_measurements(const std::filesystem::path& dir, const Config& config,
                             const BrfResult& result, std::size_t first_rami_view);

// The experiment of one band: `{band}` replaced by its name.
std::string rami_experiment(const BrfRamiSettings& rami, const std::string& band);

// The file name of one measurement for one band: `<measurement>_<model>-<experiment>.mes`.
std::string rami_file_name(const BrfRamiSettings& rami, const std::string& measurement,
                           const std::string& band);
std::string rami_file_name(const std::string& model, const std::string& experiment,
                           const std::string& measurement, const std::string& band);

}  // namespace glaswave
