// The BRF run: the scene of the first footprint built as a shot's is, the sun's photons traced
// through it, the products written.
#include "pipeline/engine/brf.hpp"

#include <tbb/task_arena.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>
#include <optional>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "pipeline/config/json_reader.hpp"
#include "pipeline/engine/inputs.hpp"
#include "pipeline/engine/machine.hpp"
#include "pipeline/engine/rami_measurements.hpp"
#include "pipeline/products/raster_writer.hpp"
#include "pipeline/shot/brf_shot.hpp"

namespace glaswave {
namespace {

// Unit vector toward zenith and azimuth (degrees, clockwise from north) in east-north-up.
Vec3 toward(double zenith_deg, double azimuth_deg) {
  const double deg = std::numbers::pi / 180.0;
  const double s = std::sin(zenith_deg * deg);
  return {s * std::sin(azimuth_deg * deg), s * std::cos(azimuth_deg * deg),
          std::cos(zenith_deg * deg)};
}

void write_json(const std::filesystem::path& path, const nlohmann::json& document) {
  AtomicFile file(path);
  std::FILE* out = std::fopen(file.part_path().c_str(), "w");
  if (!out) throw run_error(path.string(), "cannot write");
  const std::string text = document.dump(2) + "\n";
  const bool written = std::fwrite(text.data(), 1, text.size(), out) == text.size();
  if (std::fclose(out) != 0 || !written) throw run_error(path.string(), "cannot write");
  file.commit();
}

nlohmann::json brf_document(const Config& config, const BrfResult& result) {
  nlohmann::json bands = nlohmann::json::array();
  for (std::size_t band = 0; band < config.sensor.bands.size(); ++band) {
    nlohmann::json views = nlohmann::json::array();
    for (std::size_t v = 0; v < config.brf.views.size(); ++v)
      views.push_back({{"zenith_deg", config.brf.views[v].zenith_deg},
                       {"azimuth_deg", config.brf.views[v].azimuth_deg},
                       {"brf", result.brf[band][v]},
                       {"brf_stderr", result.brf_stderr[band][v]}});
    nlohmann::json entry = {{"name", config.sensor.bands[band].name},
                            {"albedo", result.albedo[band]},
                            {"views", views}};
    // RAMI's fluxes, when its measurements are asked for (the products without stay as they were).
    if (config.brf.rami || result.sky) entry["albedo_stderr"] = result.albedo_stderr[band];
    if (config.brf.rami) {
      entry["fabs"] = result.absorbed[band];
      entry["fabs_stderr"] = result.absorbed_stderr[band];
      entry["ftran"] = result.transmitted[band];
      entry["ftran_stderr"] = result.transmitted_stderr[band];
      entry["closure"] = result.closure[band];
      entry["closure_stderr"] = result.closure_stderr[band];
      entry["rami_experiment"] = rami_experiment(*config.brf.rami, config.sensor.bands[band].name);
    }
    // The layers' light (only with them: the products without stay as they were).
    if (result.sky) {
      const BrfSky& sky = *result.sky;
      entry["direct_transmittance"] = sky.direct[band];
      entry["diffuse_transmittance"] = sky.diffuse[band];
      entry["downward_flux"] = sky.downward[band];
      entry["atmosphere_absorbed"] = sky.absorbed[band];
      entry["toa_albedo"] = sky.albedo[band];
      entry["toa_albedo_stderr"] = sky.albedo_stderr[band];
      entry["toa_closure"] = sky.closure[band];
      entry["toa_closure_stderr"] = sky.closure_stderr[band];
      for (std::size_t v = 0; v < config.brf.views.size(); ++v) {
        entry["views"][v]["toa_brf"] = sky.brf[band][v];
        entry["views"][v]["toa_brf_stderr"] = sky.brf_stderr[band][v];
      }
    }
    bands.push_back(entry);
  }
  return {{"bands", bands}};
}

}  // namespace

BrfSummary run_brf(const Config& config, const BrfRequest& request,
                   const ProgressCallback& progress) {
  const auto started = std::chrono::steady_clock::now();
  check_brf(config);  // first, as check_inputs does: check and brf refuse alike
  const int pixels = static_cast<int>(config.brf.pixels());
  const std::unique_ptr<Terrain> terrain = open_terrain(config);
  const std::unique_ptr<ShotSimulator> simulator = make_shot_simulator(config, *terrain);
  const std::unique_ptr<Track> track = plan_track(config, *terrain);
  const Footprint footprint = track->footprint(0);
  if (!footprint.on_terrain)
    throw config_error("/track",
                       "the track's first footprint misses the terrain: no scene for brf");
  const double tile_half_size_m = config.brf.tile_half_size_m();
  if (const auto refused = brf_tile_error(config, *terrain, footprint)) throw *refused;

  std::optional<OutputDirectory> directory;
  if (!request.out_dir.empty()) directory.emplace(request.out_dir);
  const BrfScene scene =
      build_brf_scene(*simulator, footprint, tile_half_size_m, config.terrain.plane.has_value());
  BrfOptions options;
  options.sun_direction = -1.0 * toward(config.brf.sun_zenith_deg, config.brf.sun_azimuth_deg);
  for (const BrfView& view : config.brf.views)
    options.views.push_back(toward(view.zenith_deg, view.azimuth_deg));
  // RAMI's planes after brf.views: brf.json's views are the configuration's alone.
  for (const BrfView& view : rami_views(config.brf))
    options.views.push_back(toward(view.zenith_deg, view.azimuth_deg));
  options.photons = config.brf.photons;
  // Every order (BrfOptions' default): simulation.max_order is the lidar's.
  options.seed = config.seed;
  options.image_pixels = pixels;
  options.atmosphere = config.atmosphere;
  options.ground_height_m = footprint.ground.h_m;

  const int cores = tbb::this_task_arena::max_concurrency();
  tbb::task_arena arena(request.threads > 0 ? std::min(request.threads, cores) : cores);
  BrfResult result;
  arena.execute([&] { result = trace_brf(scene, options, progress); });

  BrfSummary summary;
  summary.document = brf_document(config, result);
  summary.photons = options.photons;
  summary.ray_queries = result.ray_queries;
  // The local frame's east and north are, to a millimetre over the tile, those of a transverse
  // Mercator projection centred on the footprint.
  char crs[256];
  std::snprintf(crs, sizeof crs,
                "+proj=tmerc +lat_0=%.10f +lon_0=%.10f +k=1 +x_0=0 +y_0=0 +datum=WGS84 +units=m "
                "+no_defs",
                footprint.ground.lat_deg, footprint.ground.lon_deg);
  summary.crs = crs;
  if (directory) {
    RasterImage image;
    image.columns = image.rows = pixels;
    const double h = tile_half_size_m, pixel_m = config.brf.image_resolution_m;
    image.geotransform = {-h, pixel_m, 0.0, h, 0.0, -pixel_m};
    image.crs = summary.crs;
    for (const LidarBand& band : config.sensor.bands) image.band_names.push_back(band.name);
    image.bands = result.image;
    write_json(request.out_dir / "brf.json", summary.document);
    write_geotiff(request.out_dir / "scene.tif", image);
    if (config.brf.rami)
      write_rami_measurements(request.out_dir / "rami", config, result, config.brf.views.size());
    directory->keep();
  }
  summary.wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return summary;
}

}  // namespace glaswave
