// The input files of a run, stamped (size, modification time, a hash of the whole file) so that
// --resume can refuse to go on once one changed: the products would be half of each input's run
// under one configuration.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace glaswave {

struct Config;

struct InputStamp {
  std::string path;
  std::uint64_t size_bytes = 0;
  std::int64_t mtime_ns = 0;
  std::uint64_t hash = 0;  // content_hash of the whole file
};

// The files a run reads besides its configuration: the DEM, crowns and stands files, the voxel
// grid, point cloud, facet trees and models, the ephemeris and the granule (a Shapefile with its
// .dbf, .shx and .prj, a folder's files), each once, in a fixed order.
std::vector<std::string> run_input_files(const Config& config);

// A 64-bit hash of `size` bytes, as content_hash goes over a file in pieces: four lanes of
// multiply-rotate rounds over 8-byte words, so that a file is hashed at memory speed (a few GB/s,
// where the byte-wise FNV-1a of the journal's frames runs under 1 GB/s). It detects a changed
// file, not a forged one: nobody gains by fooling --resume.
class ContentHash {
 public:
  void update(const char* data, std::size_t size);
  std::uint64_t digest() const;

 private:
  std::uint64_t lanes_[4] = {0x9e3779b97f4a7c15, 0xc2b2ae3d27d4eb4f, 0x165667b19e3779f9,
                             0x27d4eb2f165667c5};
  std::uint64_t total_ = 0;
  unsigned char tail_[32] = {};
  std::size_t tail_size_ = 0;
  void round(const unsigned char* block);
};

// The stamp of `path` now: Error (input) naming it when it cannot be read.
InputStamp stamp_input_file(const std::string& path);

// Each file's stamp now, in run_input_files' order.
std::vector<InputStamp> stamp_input_files(const std::vector<std::string>& paths);

// The journal's stamps against the files now: Error (config) naming the first file whose size or
// content changed (or that is gone), with what changed and what to do.
void require_unchanged_inputs(const std::vector<InputStamp>& journalled,
                              const std::vector<InputStamp>& now);

// Stamps as the journal's header keeps them, and read back (false when `bytes` is cut).
void encode_stamps(const std::vector<InputStamp>& stamps, std::string& bytes);
bool decode_stamps(const std::string& bytes, std::vector<InputStamp>& stamps);

}  // namespace glaswave
