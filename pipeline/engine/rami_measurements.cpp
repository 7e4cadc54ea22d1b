// ROMC's formats (romc.jrc.ec.europa.eu, "Format"): a BRF file is a header line (rows, columns,
// the ratio of filtered rays) and one row a view: SZA, VZA, SAA - VAA (radians), the BRF and its
// standard deviation; brf1 (the albedo) is one such row with VZA and SAA - VAA at -1. A flux
// (fabs, ftran, falb) is one line, the fraction and its standard deviation (RAMI-IV's form).
// Reals with six digits after the point.
#include "pipeline/engine/rami_measurements.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "core/atomic_file.hpp"
#include "core/error.hpp"

namespace glaswave {
namespace {

const std::vector<std::string> plane_measurements = {"brfpp",        "brfpp_co_sgl", "brfpp_uc_sgl",
                                                     "brfpp_mlt",    "brfop",        "brfop_co_sgl",
                                                     "brfop_uc_sgl", "brfop_mlt"};
const std::vector<std::string> other_measurements = {"brf1", "fabs", "ftran", "falb"};

constexpr int zeniths_per_side = 38;  // 1, 3, ..., 75 deg

bool asks_plane(const BrfRamiSettings& rami, const std::string& plane) {
  return std::any_of(rami.measurements.begin(), rami.measurements.end(),
                     [&](const std::string& m) { return m.rfind(plane, 0) == 0; });
}

}  // namespace

std::string rami_experiment(const BrfRamiSettings& rami, const std::string& band) {
  std::string experiment = rami.experiment;
  const std::string mark = "{band}";
  for (std::size_t at = experiment.find(mark); at != std::string::npos;
       at = experiment.find(mark, at + band.size()))
    experiment.replace(at, mark.size(), band);
  return experiment;
}

namespace {

std::string model_name(const BrfRamiSettings& rami) {
  return rami.model.empty() ? "glaswave" : rami.model;
}

std::string row(double sza, double vza, double relative_azimuth, double value, double error) {
  char line[160];
  std::snprintf(line, sizeof line, "%.6f %.6f %.6f %.6f %.6f\n", sza, vza, relative_azimuth, value,
                error);
  return line;
}

}  // namespace

void check_rami_request(const BrfRamiSettings& rami, std::size_t bands) {
  if (rami.measurements.empty())
    throw config_error("/brf/rami/measurements", "names no measurement");
  for (const std::string& m : rami.measurements)
    if (std::find(plane_measurements.begin(), plane_measurements.end(), m) ==
            plane_measurements.end() &&
        std::find(other_measurements.begin(), other_measurements.end(), m) ==
            other_measurements.end())
      throw config_error("/brf/rami/measurements",
                         "'" + m +
                             "' is not a measurement glaswave writes (brfpp, brfop and their "
                             "_co_sgl, _uc_sgl, _mlt parts, brf1, fabs, ftran, falb)");
  const std::string model = model_name(rami);
  if (model.size() > 10 || !std::all_of(model.begin(), model.end(),
                                        [](unsigned char c) { return std::isalnum(c) != 0; }))
    throw config_error("/brf/rami/model", "ROMC's model identifier is 1 to 10 letters and digits");
  if (rami.experiment.empty()) throw config_error("/brf/rami/experiment", "is required");
  if (rami.experiment.find_first_of("/\\ ") != std::string::npos)
    throw config_error("/brf/rami/experiment", "must not hold '/', '\\' or spaces (a file name)");
  if (bands > 1 && rami.experiment.find("{band}") == std::string::npos)
    throw config_error("/brf/rami/experiment",
                       "needs '{band}' with more than one band: an experiment is one band's");
}

std::vector<BrfView> rami_views(const BrfSettings& brf) {
  std::vector<BrfView> views;
  const double sun = brf.sun_azimuth_deg;
  for (const auto& [plane, offset_deg] : {std::pair<const char*, double>{"brfpp", 0.0},
                                          std::pair<const char*, double>{"brfop", 90.0}}) {
    if (!brf.rami || !asks_plane(*brf.rami, plane)) continue;
    // SAA - VAA = offset on the first side, offset + 180 on the second.
    for (int k = zeniths_per_side - 1; k >= 0; --k)
      views.push_back({1.0 + 2.0 * k, sun - offset_deg});
    for (int k = 0; k < zeniths_per_side; ++k)
      views.push_back({1.0 + 2.0 * k, sun - offset_deg - 180.0});
  }
  return views;
}

std::string rami_file_name(const BrfRamiSettings& rami, const std::string& measurement,
                           const std::string& band) {
  return measurement + "_" + model_name(rami) + "-" + rami_experiment(rami, band) + ".mes";
}

std::string rami_file_name(const std::string& model, const std::string& experiment,
                           const std::string& measurement, const std::string& band) {
  BrfRamiSettings rami;
  rami.model = model;
  rami.experiment = experiment;
  return rami_file_name(rami, measurement, band);
}

void write_rami_measurements(const std::filesystem::path& dir, const Config& config,
                             const BrfResult& result, std::size_t first_rami_view) {
  const BrfRamiSettings& rami = *config.brf.rami;
  const double deg = std::numbers::pi / 180.0;
  const double sza = config.brf.sun_zenith_deg * deg;
  std::filesystem::create_directories(dir);
  const std::vector<BrfView> views = rami_views(config.brf);
  // Where each plane's rows start among the result's views.
  const bool both = asks_plane(rami, "brfpp") && asks_plane(rami, "brfop");
  const std::size_t rows = 2 * zeniths_per_side;
  for (std::size_t band = 0; band < config.sensor.bands.size(); ++band) {
    const std::string& name = config.sensor.bands[band].name;
    for (const std::string& m : rami.measurements) {
      std::string text;
      if (m.rfind("brfpp", 0) == 0 || m.rfind("brfop", 0) == 0) {
        const bool orthogonal = m.rfind("brfop", 0) == 0;
        const std::size_t first = first_rami_view + (orthogonal && both ? rows : 0);
        const std::string part = m.size() > 5 ? m.substr(6) : "";
        const std::vector<std::vector<double>>* value = &result.brf;
        const std::vector<std::vector<double>>* error = &result.brf_stderr;
        if (!part.empty()) {
          const int p = part == "co_sgl"   ? brf_canopy_once
                        : part == "uc_sgl" ? brf_soil_once
                                           : brf_many_times;
          value = &result.part_brf[p];
          error = &result.part_stderr[p];
        }
        text = std::to_string(rows) + " 5 1.000000\n";
        for (std::size_t r = 0; r < rows; ++r) {
          const BrfView& view = views[first - first_rami_view + r];
          const double relative = std::fmod(
              std::fmod(config.brf.sun_azimuth_deg - view.azimuth_deg, 360.0) + 360.0, 360.0);
          text += row(sza, view.zenith_deg * deg, relative * deg, (*value)[band][first + r],
                      (*error)[band][first + r]);
        }
      } else if (m == "brf1") {
        text = "1 5 1.000000\n" +
               row(sza, -1.0, -1.0, result.albedo[band], result.albedo_stderr[band]);
      } else {
        const double value = m == "fabs"    ? result.absorbed[band]
                             : m == "ftran" ? result.transmitted[band]
                                            : result.albedo[band];
        const double error = m == "fabs"    ? result.absorbed_stderr[band]
                             : m == "ftran" ? result.transmitted_stderr[band]
                                            : result.albedo_stderr[band];
        char line[80];
        std::snprintf(line, sizeof line, "%.6f\t%.6f\n", value, error);
        text = line;
      }
      write_text_atomically(dir / rami_file_name(rami, m, name), text);
    }
  }
}

}  // namespace glaswave
