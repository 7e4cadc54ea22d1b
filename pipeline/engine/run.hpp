// The engine: a track planned, its shots simulated in parallel (and, under mpirun, shared among
// the processes) and handed in shot order to the product writers, progress reported through a
// callback. A journal of the finished shots lets a killed run be resumed. The command line and
// Python call it.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "core/directory_lock.hpp"
#include "footprints/track.hpp"
#include "pipeline/config/config.hpp"
#include "pipeline/engine/machine.hpp"
#include "pipeline/shot/shot_simulator.hpp"

namespace glaswave {

struct RunRequest {
  std::filesystem::path out_dir;
  int threads = 0;                                    // 0: every core
  std::optional<std::int64_t> first_shot, last_shot;  // --shots A:B, half-open
  std::string command_line;                           // for the products' history
  // Finish the interrupted run in out_dir (its journal): the shots it finished are kept. When
  // out_dir does not exist the run starts from the beginning.
  bool resume = false;
};

struct RunSummary {
  std::int64_t shots = 0;
  std::int64_t shots_flagged = 0;
  std::int64_t ray_queries = 0;
  double wall_s = 0.0;
  std::string vertical_datum;         // what the terrain's heights were measured from, in words
  std::vector<std::string> warnings;  // what the user should know, one line each
  std::int64_t shots_resumed = 0;     // shots taken from an interrupted run's journal
};

// Called after each batch of shots with (shots done, shots in all).
using ProgressCallback = std::function<void(std::int64_t, std::int64_t)>;
// Receives each simulated record with its index in the track.
using RecordConsumer = std::function<void(std::int64_t, const ShotRecord&)>;

// Simulates records [first, last) of the track in batches on `threads` threads (0: every core),
// handing each record to `consume` in record order: the run's one batch loop, on this process
// alone (Cluster::alone). Returns the ray queries made.
std::int64_t simulate_records(const ShotSimulator& simulator, const Track& track,
                              std::int64_t first, std::int64_t last, int threads,
                              const RecordConsumer& consume, const ProgressCallback& progress);

// A run's output directory: refused when it exists, made, and removed again if the run leaves
// it empty (a run that fails: the writers remove their parts). With `resume`, a directory that
// holds an interrupted run (its journal, or nothing but .part files) is taken as it is and one
// that does not exist is made; one that holds anything else is refused.
class OutputDirectory {
 public:
  explicit OutputDirectory(std::filesystem::path path, bool resume = false);
  ~OutputDirectory();
  OutputDirectory(const OutputDirectory&) = delete;
  OutputDirectory& operator=(const OutputDirectory&) = delete;
  void keep() { kept_ = true; }
  // Whether an interrupted run's journal is there to resume.
  bool has_journal() const { return has_journal_; }

 private:
  std::filesystem::path path_;
  std::unique_ptr<DirectoryLock> lock_;  // taken before anything in the directory is looked at
  bool kept_ = false;
  bool has_journal_ = false;
};

// What `check` found: the configuration's inputs opened and its track planned.
struct CheckSummary {
  std::int64_t shots = 0;              // records of the track (an orbit's: those on the terrain)
  std::int64_t sequence_length = 0;    // shot numbers of the track
  std::int64_t shots_off_terrain = 0;  // records whose beam misses the terrain (of those located)
  std::int64_t shots_located = 0;      // records located: every one, or an even sample of a long
                                       // track (max_located_shots)
  std::vector<std::string> warnings;   // what the user should know, one line each
  std::optional<SharedScenes> shared_scenes;  // the strips its shots share, as run plans them
};

// Opens every input of the configuration (DEM, crowns and stands, ephemeris) and plans the
// track, simulating nothing: what `check` does. Throws Error as a run would.
CheckSummary check_inputs(const Config& config);

// Simulates the shots and writes the products under request.out_dir, which must not exist
// (unless request.resume). On failure nothing is left under a product's final name; a failed
// new run leaves nothing at all, a killed one its .part files and journal for --resume. Under
// mpirun every process calls it: the shots are shared, rank 0 writes and reports progress.
RunSummary run_simulation(const Config& config, const RunRequest& request,
                          const ProgressCallback& progress);

}  // namespace glaswave
