// The run: shots simulated in batches on a thread pool, written in shot order.
#include "pipeline/engine/run.hpp"

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <chrono>
#include <memory>

#include "core/error.hpp"
#include "footprints/track.hpp"
#include "pipeline/engine/inputs.hpp"
#include "pipeline/engine/shot_simulation.hpp"
#include "pipeline/products/product_writer.hpp"

namespace glaswave {

OutputDirectory::OutputDirectory(std::filesystem::path path) : path_(std::move(path)) {
  std::error_code error;
  if (std::filesystem::exists(path_, error))
    throw config_error(path_.string(),
                       "output directory exists; remove it or choose another --out");
  std::filesystem::create_directories(path_, error);
  if (error)
    throw config_error(path_.string(), "cannot create the output directory: " + error.message());
}

OutputDirectory::~OutputDirectory() {
  std::error_code ignored;
  if (!kept_ && std::filesystem::is_empty(path_, ignored)) std::filesystem::remove(path_, ignored);
}

std::int64_t simulate_records(const ShotSimulator& simulator, const Track& track,
                              std::int64_t first, std::int64_t last, int threads,
                              const RecordConsumer& consume, const ProgressCallback& progress) {
  // More threads than cores would only wait for each other (and TBB would warn on stderr).
  const int cores = tbb::this_task_arena::max_concurrency();
  threads = threads > 0 ? std::min(threads, cores) : cores;
  tbb::task_arena arena(threads);
  // Batches keep memory bounded on long tracks and hand records on in record order.
  const std::int64_t batch_size = std::max<std::int64_t>(8, 4 * threads);
  std::atomic<std::int64_t> ray_queries{0};
  for (std::int64_t batch_first = first; batch_first < last; batch_first += batch_size) {
    const std::int64_t batch_last = std::min(batch_first + batch_size, last);
    const std::vector<Footprint> footprints = track.footprints(batch_first, batch_last);
    std::vector<ShotRecord> records(footprints.size());
    arena.execute([&] {
      tbb::parallel_for(std::size_t{0}, footprints.size(), [&](std::size_t i) {
        std::int64_t queries = 0;
        records[i] = simulator.simulate(footprints[i], &queries);
        ray_queries += queries;
      });
    });
    for (std::size_t i = 0; i < records.size(); ++i)
      consume(batch_first + static_cast<std::int64_t>(i), records[i]);
    if (progress) progress(batch_last - first, last - first);
  }
  return ray_queries;
}

CheckSummary check_inputs(const Config& config) {
  check_run(config);  // what run refuses before simulating
  const std::unique_ptr<Terrain> terrain = open_terrain(config);
  // The forest reads its crowns file and checks what the configuration cannot alone.
  grow_forest(config);
  const std::unique_ptr<Track> track = plan_track(config, *terrain);
  CheckSummary summary;
  summary.shots = track->size();
  summary.sequence_length = track->sequence_length();
  std::vector<std::array<double, 2>> centres;
  for (std::int64_t record = 0; record < track->size(); ++record) {
    const Footprint footprint = track->footprint(record);
    summary.shots_off_terrain += footprint.on_terrain ? 0 : 1;
    if (footprint.on_terrain)
      centres.push_back({footprint.ground.lat_deg, footprint.ground.lon_deg});
  }
  if (const auto warning = stands_off_track(config, centres)) summary.warnings.push_back(*warning);
  return summary;
}

RunSummary run_simulation(const Config& config, const RunRequest& request,
                          const ProgressCallback& progress) {
  const auto started = std::chrono::steady_clock::now();
  check_run(config);  // first, as check_inputs does: check and run refuse alike

  const std::unique_ptr<Terrain> terrain = open_terrain(config);
  // The products record what the DEM's heights were measured from, as the terrain chose it (its
  // own vertical CRS wins over terrain.vertical_datum). The simulator grows the forest before
  // the track is planned, in check_inputs' order, so that both name the same first fault.
  Config used = config;
  used.resolved["terrain"]["vertical_datum"] = terrain->vertical_datum().key;
  const ShotSimulator simulator(used, *terrain);
  // --shots A:B selects shot numbers; an orbit's records are only the shots on the terrain.
  const std::unique_ptr<Track> planned = plan_track(config, *terrain);
  const Track& track = *planned;
  const std::int64_t length = track.sequence_length();
  const auto selected =
      track.records_of_shots(request.first_shot.value_or(0), request.last_shot.value_or(length));
  const std::int64_t first = selected.first, last = selected.second;  // records
  if (first >= last)
    throw config_error("--shots", "selects no shot of the track's " + std::to_string(length) +
                                      (track.size() < length ? " (" + std::to_string(track.size()) +
                                                                   " on the terrain)"
                                                             : std::string()));

  OutputDirectory directory(request.out_dir);
  RunInfo info = simulator.run_info(last - first, request.command_line);
  info.vertical_datum = terrain->vertical_datum().description;
  const ProductSettings settings{config.output.netcdf, config.output.geojson,
                                 config.output.footprints_format == "GPKG"
                                     ? FootprintsFormat::gpkg
                                     : FootprintsFormat::geojson};
  const std::vector<std::unique_ptr<ProductWriter>> writers =
      make_writers(request.out_dir, settings, info);

  RunSummary summary;
  std::vector<std::array<double, 2>> centres;
  summary.ray_queries = simulate_records(
      simulator, track, first, last, request.threads,
      [&](std::int64_t record, const ShotRecord& shot) {
        const std::int64_t index = record - first;
        for (const auto& writer : writers) writer->write(index, shot);
        if (shot.quality_flag != quality_good) ++summary.shots_flagged;
        centres.push_back({shot.lat_deg, shot.lon_deg});
      },
      progress);
  if (const auto warning = stands_off_track(config, centres)) summary.warnings.push_back(*warning);

  summary.shots = last - first;
  summary.vertical_datum = terrain->vertical_datum().description;
  summary.wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  RunStats stats;
  stats.ray_queries = summary.ray_queries;
  stats.wall_s = summary.wall_s;
  stats.shots_flagged = summary.shots_flagged;
  for (const auto& writer : writers) writer->finish(stats);
  directory.keep();
  return summary;
}

}  // namespace glaswave
