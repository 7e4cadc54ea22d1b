// The run: shots simulated in batches on a thread pool (and shared among mpirun's processes),
// journalled, and written in shot order by rank 0.
#include "pipeline/engine/run.hpp"

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <thread>

#include "core/error.hpp"
#include "footprints/atlas_beams.hpp"
#include "footprints/track.hpp"
#include "pipeline/engine/cluster.hpp"
#include "pipeline/engine/inputs.hpp"
#include "pipeline/engine/journal.hpp"
#include "pipeline/engine/machine.hpp"
#include "pipeline/engine/rami_lidar.hpp"
#include "pipeline/products/hdf5_granule_writer.hpp"
#include "pipeline/products/product_writer.hpp"
#include "pipeline/products/record_codec.hpp"
#include "pipeline/shot/cloud_layers.hpp"
#include "pipeline/shot/photon_receiver.hpp"

namespace glaswave {
namespace {

namespace fs = std::filesystem;

bool is_part(const fs::directory_entry& entry) { return entry.path().extension() == ".part"; }

// Records [a, b) of the track on the arena's threads; adds their ray queries to `queries`.
std::vector<ShotRecord> simulate_range(const ShotSimulator& simulator, const Track& track,
                                       std::int64_t a, std::int64_t b, tbb::task_arena& arena,
                                       std::int64_t& queries) {
  b = std::min(b, track.size());
  if (a >= b) return {};
  std::vector<ShotRecord> records(static_cast<std::size_t>(b - a));
  std::atomic<std::int64_t> ray_queries{0};
  arena.execute([&] {
    tbb::parallel_for(std::size_t{0}, records.size(), [&](std::size_t i) {
      std::int64_t n = 0;
      // Each thread places its own shots on the track (Track::footprints, one at a time).
      const Footprint footprint = track.footprint(a + static_cast<std::int64_t>(i));
      // Roughness too fine to mesh under this beam is refused there, named in /terrain.
      records[i] = at_section("/terrain", [&] { return simulator.simulate(footprint, &n); });
      ray_queries += n;
    });
  });
  queries += ray_queries;
  return records;
}

// The cores a process may run on are its affinity's (TBB counts those), which can be fewer than
// the machine's: mpirun binds each process to one core when it starts two or fewer (to a socket
// beyond), taskset and batch systems narrow it too. A warning when that leaves the process fewer
// threads than `--threads` asks for, or, under mpirun, than its share of the machine.
std::optional<std::string> narrowed_threads_warning(int threads, const Cluster& cluster) {
  const int usable = tbb::this_task_arena::max_concurrency();
  const int machine = static_cast<int>(std::thread::hardware_concurrency());
  const int processes_here = cluster.local_size();
  const int meant =
      threads > 0 ? std::min(threads, machine) : std::max(1, machine / std::max(1, processes_here));
  // Alone, --threads 0 means the cores it may run on: a batch system's cpuset is what was meant.
  if (usable >= meant || (threads == 0 && !cluster.launched())) return std::nullopt;
  const int runs = threads_of_process(threads, processes_here);
  std::string text = "--threads " + std::to_string(threads) + ": this process may run on " +
                     std::to_string(usable) + " of the machine's " + std::to_string(machine) +
                     " cores, so it runs " + std::to_string(runs) + " thread" +
                     (runs == 1 ? "" : "s") + " where " + std::to_string(meant) + " were meant";
  if (cluster.launched())
    text +=
        " (mpirun binds each process to a core when it starts two or fewer: give mpirun "
        "--bind-to none)";
  return text;
}

// Receives a batch of records in order: the index of its first, the records, the ray queries
// they took.
using BatchConsumer = std::function<void(std::int64_t, std::span<const ShotRecord>, std::int64_t)>;

// One batch of records: this process's block of it simulated, then on rank 0 the whole batch
// gathered from every rank.
struct Batch {
  std::int64_t first = 0, last = 0;  // the batch's records
  std::vector<ShotRecord> records;
  std::int64_t queries = 0;
  std::string bytes;  // this block for rank 0, when there are other ranks
  std::exception_ptr failure;
};

// Every rank, in the same order: rank 0 gets the batch's records from every rank.
void gather_batch(Cluster& cluster, Batch& batch) {
  cluster.agree(batch.failure);
  if (cluster.size() == 1) return;
  std::vector<std::string> parts = cluster.gather(batch.bytes);
  batch.records.clear();
  batch.queries = 0;
  for (const std::string& part : parts) {  // rank 0 only: the others get none
    std::int64_t part_queries = 0;
    std::memcpy(&part_queries, part.data(), sizeof part_queries);
    batch.queries += part_queries;
    std::size_t offset = sizeof part_queries;
    while (offset < part.size()) batch.records.push_back(decode_record(part, offset));
  }
}

// The one batch loop. Records [first, last) shared among the cluster's processes: each batch is cut
// into one block per rank, every rank simulates its block, rank 0 gathers the records in order and
// alone hands them to `consume` and reports progress, while every rank simulates the next batch
// (the writing would otherwise leave all but one core idle). A failure anywhere ends every rank.
void simulate_batches(Cluster& cluster, const ShotSimulator& simulator, const Track& track,
                      std::int64_t first, std::int64_t last, int threads,
                      const BatchConsumer& consume, const ProgressCallback& progress,
                      std::int64_t progress_first) {
  if (first >= last) return;
  threads = threads_of_process(threads, cluster.local_size());
  tbb::task_arena arena(threads);
  // Batches keep memory bounded on long tracks and hand records on in record order. Shots that
  // share their stretch's scene take a few tenths of a millisecond: in batches of 4 a thread the
  // threads' handing over (futexes, yields) took a tenth of a photon-counting run's time.
  const std::int64_t shots_a_thread = simulator.shares_scenes() ? 64 : 4;
  const std::int64_t block = std::max<std::int64_t>(8, shots_a_thread * threads);
  const std::int64_t batch_size = block * cluster.size();
  auto simulate_batch = [&](std::int64_t batch_first, Batch& batch) {
    batch.first = batch_first;
    batch.last = std::min(batch_first + batch_size, last);
    const std::int64_t a = std::min(batch_first + cluster.rank() * block, batch.last);
    const std::int64_t b = std::min(a + block, batch.last);
    try {
      batch.records = simulate_range(simulator, track, a, b, arena, batch.queries);
      if (cluster.size() > 1) {
        batch.bytes.append(reinterpret_cast<const char*>(&batch.queries), sizeof batch.queries);
        for (const ShotRecord& record : batch.records) encode_record(record, batch.bytes);
      }
    } catch (...) {
      batch.failure = std::current_exception();
    }
  };
  auto gather = [&](Batch& batch) { gather_batch(cluster, batch); };

  Batch current;
  simulate_batch(first, current);
  gather(current);
  for (;;) {
    const bool more = current.last < last;
    Batch next;
    tbb::task_group simulating;
    if (more) arena.execute([&] { simulating.run([&] { simulate_batch(current.last, next); }); });
    std::exception_ptr failure;
    try {
      if (cluster.rank() == 0) {
        consume(current.first, current.records, current.queries);
        if (progress) progress(current.last - progress_first, last - progress_first);
      }
    } catch (...) {
      failure = std::current_exception();
    }
    arena.execute([&] { simulating.wait(); });
    cluster.agree(failure);
    if (!more) return;
    gather(next);
    current = std::move(next);
  }
}

// What every process sets up before a shot is simulated.
struct RunSetup {
  std::unique_ptr<Terrain> terrain;
  Config used;
  std::unique_ptr<ShotSimulator> simulator;
  std::unique_ptr<Track> track;
  std::int64_t first = 0, last = 0;  // records
};

std::unique_ptr<RunSetup> set_up(const Config& config, const RunRequest& request) {
  check_run(config);  // first, as check_inputs does: check and run refuse alike
  auto setup = std::make_unique<RunSetup>();
  setup->terrain = open_terrain(config);
  // The products record what the DEM's heights were measured from, as the terrain chose it (its
  // own vertical CRS wins over terrain.vertical_datum). The simulator grows the forest before
  // the track is planned, in check_inputs' order, so that both name the same first fault.
  setup->used = config;
  setup->used.resolved["terrain"]["vertical_datum"] = setup->terrain->vertical_datum().key;
  setup->simulator = make_run_shot_simulator(setup->used, *setup->terrain);
  // --shots A:B selects shot numbers; an orbit's records are only the shots on the terrain.
  setup->track = plan_track(config, *setup->terrain);
  const Track& track = *setup->track;
  setup->simulator->share_scenes_along(track);
  // The strips' scenes the shots will share, counted as check counts them.
  if (const auto shared = shared_scenes(*setup->simulator, track))
    check_run_memory(estimate_run_memory(config, &*shared));
  const std::int64_t length = track.sequence_length();
  const auto selected =
      track.records_of_shots(request.first_shot.value_or(0), request.last_shot.value_or(length));
  setup->first = selected.first;
  setup->last = selected.second;
  if (setup->first >= setup->last)
    throw config_error("--shots", "selects no shot of the track's " + std::to_string(length) +
                                      (track.size() < length ? " (" + std::to_string(track.size()) +
                                                                   " on the terrain)"
                                                             : std::string()));
  return setup;
}

// Rank 0's side of a run: the directory, the journal and the writers. A new run that fails
// removes its journal with the rest; a resumed one keeps it, to be resumed again.
struct RunOutput {
  std::unique_ptr<OutputDirectory> directory;
  std::unique_ptr<RunJournal> journal;
  std::vector<std::unique_ptr<ProductWriter>> writers;
  bool resumed = false;
  bool complete = false;
  std::int64_t written = 0;                    // records handed to the writers
  std::vector<std::array<double, 2>> centres;  // the shots' (lat, lon), for stands_off_track

  // One record to every writer, counted in the summary.
  void take(const ShotRecord& shot, RunSummary& summary) {
    for (const auto& writer : writers) writer->write(written, shot);
    ++written;
    if (shot.quality_flag != quality_good) ++summary.shots_flagged;
    centres.push_back({shot.lat_deg, shot.lon_deg});
  }

  ~RunOutput() {
    writers.clear();  // their .part files go first
    if (journal && !complete && !resumed) journal->remove();
  }
};

}  // namespace

OutputDirectory::OutputDirectory(std::filesystem::path path, bool resume) : path_(std::move(path)) {
  std::error_code error;
  if (fs::exists(path_, error)) {
    // Another run writing here (two --resume started together) must not be looked at half-way.
    if (fs::is_directory(path_, error)) lock_ = std::make_unique<DirectoryLock>(path_);
    has_journal_ = fs::exists(path_ / RunJournal::kFileName, error);
    bool only_parts = true;  // a run killed before its journal was made
    for (const auto& entry : fs::directory_iterator(path_, error))
      only_parts = only_parts && ((entry.is_regular_file() && is_part(entry)) ||
                                  entry.path().filename() == DirectoryLock::kFileName);
    if (resume && !has_journal_ && !only_parts)
      throw config_error(path_.string(),
                         "holds no interrupted run to resume (no " +
                             std::string(RunJournal::kFileName) +
                             "): its products are finished, or it is not a glaswave run");
    if (!resume && has_journal_)
      throw config_error(path_.string(),
                         "holds an interrupted run: finish it with the same command and "
                         "--resume, or remove the directory");
    if (!resume)
      throw config_error(path_.string(),
                         "output directory exists; remove it or choose another --out");
    kept_ = true;  // it was there before this run
    return;
  }
  fs::create_directories(path_, error);
  if (error)
    throw config_error(path_.string(), "cannot create the output directory: " + error.message());
  // A run started with this one may have created the directory too and hold it: then it is
  // that run's, and this constructor's failure leaves it alone.
  lock_ = std::make_unique<DirectoryLock>(path_);
}

OutputDirectory::~OutputDirectory() {
  lock_.reset();  // its file goes first, so that an empty directory is seen as one
  std::error_code ignored;
  if (!kept_ && fs::is_empty(path_, ignored)) fs::remove(path_, ignored);
}

std::int64_t simulate_records(const ShotSimulator& simulator, const Track& track,
                              std::int64_t first, std::int64_t last, int threads,
                              const RecordConsumer& consume, const ProgressCallback& progress) {
  std::int64_t ray_queries = 0;
  simulate_batches(
      Cluster::alone(), simulator, track, first, last, threads,
      [&](std::int64_t batch_first, std::span<const ShotRecord> records, std::int64_t queries) {
        for (std::size_t i = 0; i < records.size(); ++i)
          consume(batch_first + static_cast<std::int64_t>(i), records[i]);
        ray_queries += queries;
      },
      progress, first);
  return ray_queries;
}

namespace {

// brf refuses a tile beyond a DEM's data (brf_tile_error); check only warns, since a
// configuration may be meant for run alone.
std::optional<std::string> brf_tile_off_terrain(const Config& config, const Terrain& terrain,
                                                const Track& track) {
  if (track.size() == 0) return std::nullopt;
  const Footprint first = track.footprint(0);
  if (!first.on_terrain) return std::nullopt;
  const auto refused = brf_tile_error(config, terrain, first);
  if (!refused) return std::nullopt;
  return std::string("brf would refuse this configuration: ") + refused->what();
}

}  // namespace

// check locates at most this many footprints, evenly spread over a longer track: a footprint
// costs about 4 us, and a pass of 10^9 shots (run_limits::track_shots) took check over an hour.
// The off-terrain count of a longer track is its sample's, scaled; the warnings that look at
// the footprints (stands and crowns off the track) see the sample.
constexpr std::int64_t max_located_shots = 1'000'000;

CheckSummary check_inputs(const Config& config) {
  check_run(config);  // what run refuses before simulating
  check_brf(config);  // ... and brf
  const std::unique_ptr<Terrain> terrain = open_terrain(config);
  // The shot simulator as run makes it: its vegetation reads its files (a crowns file, a voxel
  // grid's header) and checks what the configuration cannot alone.
  const std::unique_ptr<ShotSimulator> simulator = make_shot_simulator(config, *terrain);
  const VegetationSource* vegetation = simulator->vegetation();
  // A voxel grid's values are read where the beams are, as run reads them (NaN under a beam).
  const bool read_vegetation = vegetation && vegetation->checks_regions();
  const std::unique_ptr<Track> track = plan_track(config, *terrain);
  CheckSummary summary;
  // The strips' scenes the shots will share, as run plans them (and refuses them).
  simulator->share_scenes_along(*track);
  summary.shared_scenes = shared_scenes(*simulator, *track);
  if (summary.shared_scenes) check_run_memory(estimate_run_memory(config, &*summary.shared_scenes));
  summary.shots = track->size();
  summary.sequence_length = track->sequence_length();
  summary.warnings = config.warnings;
  for (const std::string& warning : track->warnings()) summary.warnings.push_back(warning);
  std::vector<std::array<double, 2>> centres;
  const std::int64_t step = (track->size() + max_located_shots - 1) / max_located_shots;
  for (std::int64_t record = 0; record < track->size(); record += std::max<std::int64_t>(1, step)) {
    const Footprint footprint = track->footprint(record);
    ++summary.shots_located;
    summary.shots_off_terrain += footprint.on_terrain ? 0 : 1;
    if (footprint.on_terrain)
      centres.push_back({footprint.ground.lat_deg, footprint.ground.lon_deg});
    if (footprint.on_terrain && read_vegetation)
      at_section("/canopy", [&] { simulator->check_vegetation(footprint); });
  }
  if (summary.shots_located < summary.shots && summary.shots_off_terrain > 0)
    summary.shots_off_terrain = static_cast<std::int64_t>(std::llround(
        double(summary.shots_off_terrain) * double(summary.shots) / double(summary.shots_located)));
  if (const auto warning = stands_off_track(config, centres)) summary.warnings.push_back(*warning);
  if (const auto warning = brf_tile_off_terrain(config, *terrain, *track))
    summary.warnings.push_back(*warning);
  if (const auto warning = crowns_off_track(config, vegetation, centres))
    summary.warnings.push_back(*warning);
  // Roughness too fine to mesh under the beam is refused where a shot builds its ground: the
  // first footprint's scene is built here, so that check refuses it as run does.
  if (config.terrain.roughness.rms_m > 0.0) {
    for (std::int64_t record = 0; record < track->size(); ++record)
      if (const Footprint footprint = track->footprint(record); footprint.on_terrain) {
        at_section("/terrain", [&] { simulator->check_scene(footprint); });
        break;
      }
  }
  return summary;
}

namespace {

// The ICESat-2 granules of a photon-counting run (on unless output.atl03/atl08 say otherwise),
// for its beams.
Icesat2ProductSettings icesat2_product_settings(const Config& config) {
  Icesat2ProductSettings s;
  if (!receiver_traits(config.sensor.receiver).atlas_beams) return s;
  s.atl03 = config.output.atl03.value_or(true);
  s.atl08 = config.output.atl08.value_or(true);
  s.beams.clear();
  // A pass's beams fly their own ground tracks about it; another track is the beam's own.
  const bool pass = config.track.type == TrackType::pass;
  const AtlasOrientation orientation = atlas_orientation(config.sensor.sc_orient);
  // The photon receiver's pulse: the first band's energy times the beam's ratio to a strong one.
  const double strong_J = config.sensor.bands.empty()
                              ? std::nan("")
                              : config.sensor.bands.front().pulse_energy_mJ * 1e-3;
  // The photons a joule of the band's whole pulse's return gives the beam: what rt on ATL03
  // scales its table by (the receiver's efficiency over a photon's energy, and the beam's share).
  const double photons_per_J =
      config.sensor.bands.empty()
          ? std::nan("")
          : detected_photons_per_J(config.sensor, config.sensor.bands.front().wavelength_nm);
  for (const AtlasBeam& beam : select_atlas_beams(config.sensor.beams, orientation))
    s.beams.push_back({beam.name, beam.strong, beam.spot_number, pass ? beam.across_m : 0.0,
                       strong_J * beam.energy_ratio, photons_per_J * beam.energy_ratio});
  s.sc_orient = static_cast<std::int8_t>(orientation);
  s.dead_time_ns = config.sensor.dead_time_ns;
  // ATL08's cloud flags: the layers ATL09 would report, at the beams' one band.
  if (config.atmosphere) s.cloud_layers = reported_cloud_layers(*config.atmosphere, 0);
  return s;
}

// The identity a journal is checked against: what decides the records (the resolved
// configuration, the records selected) and how they are stored (the version).
std::string run_identity(const RunInfo& info, std::int64_t first, std::int64_t last) {
  return info.config_json + "\n" + std::to_string(first) + ":" + std::to_string(last) +
         "\nglaswave " + GLASWAVE_VERSION + " journal 3";
}

// Rank 0: the output directory made (or taken, to resume), the journal and the writers begun,
// and an interrupted run's records handed to the writers again.
std::unique_ptr<RunOutput> open_output(const RunSetup& setup, const RunRequest& request,
                                       const RunInfo& info, RunSummary& summary) {
  auto output = std::make_unique<RunOutput>();
  output->directory = std::make_unique<OutputDirectory>(request.out_dir, request.resume);
  const fs::path journal_path = request.out_dir / RunJournal::kFileName;
  const std::string identity = run_identity(info, setup.first, setup.last);
  output->resumed = output->directory->has_journal();
  // Each input file read whole once more for its hash: a resume over changed inputs is refused.
  const std::vector<InputStamp> inputs = stamp_input_files(run_input_files(setup.used));
  if (!output->resumed)
    output->journal = std::make_unique<RunJournal>(journal_path, identity, inputs);
  // The products are written again from the journal: an interrupted run's parts go.
  std::error_code ignored;
  if (request.resume)
    for (const auto& entry : fs::directory_iterator(request.out_dir, ignored))
      if (is_part(entry)) fs::remove(entry.path(), ignored);
  const Config& config = setup.used;
  ProductSettings settings;
  settings.netcdf = config.output.netcdf;
  settings.footprints = config.output.footprints;
  settings.footprints_format = config.output.footprints_format == "GPKG"
                                   ? FootprintsFormat::gpkg
                                   : FootprintsFormat::geojson;
  settings.glas_topex = config.output.glas_ellipsoid == "topex";
  settings.switches = config.output.switches;  // the writers' own keys
  // GLAH14's cloud flag: the layers found at GLAS's 1064 nm channel, as ATL08's at 532 nm.
  if (config.atmosphere && switched_on(settings.switches, "glah14"))
    settings.glas_cloud_layers =
        reported_cloud_layers(*config.atmosphere, nearest_band(info, 1064.0));
  output->writers = make_writers(request.out_dir, settings, info, icesat2_product_settings(config));
  if (config.output.rami)
    output->writers.push_back(make_rami_lidar_writer(request.out_dir, config, info));
  if (output->resumed) {
    RunOutput& out = *output;
    out.journal = RunJournal::resume(
        journal_path, identity, [&](const ShotRecord& shot) { out.take(shot, summary); },
        summary.ray_queries, inputs);
    summary.shots_resumed = out.written;
  }
  return output;
}

// Rank 0's end of a run: the stands' and crowns' warnings, the products completed, the journal
// removed.
void finish_output(RunOutput& output, const Config& config, const VegetationSource* vegetation,
                   RunSummary& summary, std::chrono::steady_clock::time_point started) {
  if (const auto warning = stands_off_track(config, output.centres))
    summary.warnings.push_back(*warning);
  if (const auto warning = crowns_off_track(config, vegetation, output.centres))
    summary.warnings.push_back(*warning);
  summary.wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  RunStats stats;
  stats.ray_queries = summary.ray_queries;
  stats.wall_s = summary.wall_s;
  stats.shots_flagged = summary.shots_flagged;
  for (const auto& writer : output.writers) writer->finish(stats);
  output.complete = true;
  output.journal->remove();
  output.directory->keep();
}

}  // namespace

RunSummary run_simulation(const Config& config, const RunRequest& request,
                          const ProgressCallback& progress) {
  const auto started = std::chrono::steady_clock::now();
  Cluster& cluster = Cluster::world();
  std::unique_ptr<RunSetup> setup;
  std::exception_ptr failure;
  try {
    setup = set_up(config, request);
  } catch (...) {
    failure = std::current_exception();
  }
  cluster.agree(failure);
  const std::int64_t first = setup->first, last = setup->last;

  RunInfo info = run_info(setup->used, *setup->simulator, last - first, request.command_line);
  info.vertical_datum = setup->terrain->vertical_datum().description;
  RunSummary summary;
  summary.warnings = config.warnings;
  // The track's own (a granule's fill positions skipped), as check says them.
  for (const std::string& warning : setup->track->warnings()) summary.warnings.push_back(warning);
  std::unique_ptr<RunOutput> output;
  try {
    if (cluster.rank() == 0) output = open_output(*setup, request, info, summary);
  } catch (...) {
    failure = std::current_exception();
  }
  cluster.agree(failure);
  const std::int64_t done = cluster.broadcast(output ? output->written : 0);
  if (cluster.rank() == 0)
    if (auto warning = narrowed_threads_warning(request.threads, cluster))
      summary.warnings.push_back(std::move(*warning));

  simulate_batches(
      cluster, *setup->simulator, *setup->track, first + done, last, request.threads,
      [&](std::int64_t, std::span<const ShotRecord> records, std::int64_t queries) {
        for (const ShotRecord& shot : records) output->take(shot, summary);
        output->journal->append(records, queries);
        summary.ray_queries += queries;
      },
      progress, first);

  summary.shots = last - first;
  summary.vertical_datum = setup->terrain->vertical_datum().description;
  try {
    if (cluster.rank() == 0)
      finish_output(*output, config, setup->simulator->scenes().vegetation(), summary, started);
  } catch (...) {
    failure = std::current_exception();
  }
  cluster.agree(failure);
  return summary;
}

}  // namespace glaswave
