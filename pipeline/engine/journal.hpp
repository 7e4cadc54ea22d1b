// The run journal: the records of the shots a run has finished, kept beside the products'
// .part files so that a run killed at any moment (SIGKILL, a machine lost) can be finished
// with --resume and still write products identical to an uninterrupted run. It is a header
// (the run's identity: a hash of the configuration and the shots; its input files' stamps) and
// frames of records, one
// per batch, each with its checksum and the index of its first record; a frame torn by the kill
// is dropped on resume, and a whole frame out of its place (repeated, missing, swapped) refuses
// the journal. Frames are
// flushed to the disk at most about once a second.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "pipeline/engine/input_stamps.hpp"
#include "pipeline/products/shot_record.hpp"

namespace glaswave {

class RunJournal {
 public:
  // The journal's name in the output directory.
  static constexpr const char* kFileName = "glaswave.journal";
  // A frame's records, uncompressed: a frame is closed once they pass this many bytes, so that
  // LZ4 (2 GB at most at once) takes any batch.
  static constexpr std::size_t kFrameBytes = std::size_t{8} << 20;

  // Creates `path` for a run of identity `identity` (any text; only its hash is kept) reading
  // the input files `inputs` (their stamps are kept).
  RunJournal(std::filesystem::path path, const std::string& identity,
             const std::vector<InputStamp>& inputs = {});
  ~RunJournal();
  RunJournal(const RunJournal&) = delete;
  RunJournal& operator=(const RunJournal&) = delete;

  // Opens the journal at `path` to go on with it: checks that it belongs to a run of the same
  // identity (Error (config) naming --resume if not) and the same input files (`inputs`, their
  // stamps now: Error (config) naming the first file that changed), hands every record it holds to
  // `consume` in order, drops a torn last frame, and returns the journal ready to append.
  // `ray_queries` receives the ray queries of the records handed on.
  static std::unique_ptr<RunJournal> resume(const std::filesystem::path& path,
                                            const std::string& identity,
                                            const std::function<void(const ShotRecord&)>& consume,
                                            std::int64_t& ray_queries,
                                            const std::vector<InputStamp>& inputs = {});

  // Appends a frame of records (the next of the run, in order) and the ray queries they took.
  // Throws Error (run) naming the journal when it cannot be written (a full disk).
  void append(std::span<const ShotRecord> records, std::int64_t ray_queries);

  // Flushes what was appended to the disk.
  void sync();

  // Removes the journal: the run is complete.
  void remove();

 private:
  RunJournal(std::filesystem::path path, int fd);
  void write_all(const char* bytes, std::size_t size);
  void write_frame(const std::string& raw, std::size_t records, std::int64_t ray_queries);

  std::filesystem::path path_;
  int fd_ = -1;
  double last_sync_s_ = 0.0;
  std::string raw_;    // a frame's records, uncompressed; kept, as frame_, for the next frame
  std::string frame_;  // a frame as written: header, LZ4 payload, checksum
  std::uint64_t records_ = 0;  // records in the journal: the index of the next frame's first
};

}  // namespace glaswave
