// The run journal on disk: a header (magic, identity hash, the input files' stamps: their bytes'
// length, then encode_stamps' words), then frames: a marker, the
// index in the run of the frame's first record, the record count, the ray queries, the payload's
// size and its size uncompressed, the payload (records as record_codec writes them, compressed with
// LZ4) and an FNV-1a checksum of all that. Written with POSIX calls so that every write and flush
// is checked.
#include "pipeline/engine/journal.hpp"

#include <fcntl.h>
#include <lz4.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/input_file.hpp"
#include "core/write_error.hpp"
#include "pipeline/products/record_codec.hpp"

namespace glaswave {
namespace {

constexpr std::uint64_t kMagic = 0x35304c4e524a5747;  // "GWJRNL05"
constexpr std::uint64_t kFrameMarker = 0x454d415246574721;
// A run's longest wait between flushes of the journal to the disk.
constexpr double kSyncInterval_s = 1.0;
// What LZ4 compresses at once: no frame's records may pass it.
constexpr std::size_t kLargestFrame = LZ4_MAX_INPUT_SIZE;

std::uint64_t fnv1a(const char* data, std::size_t size, std::uint64_t hash = 0xcbf29ce484222325) {
  for (std::size_t i = 0; i < size; ++i) {
    hash ^= static_cast<unsigned char>(data[i]);
    hash *= 0x100000001b3;
  }
  return hash;
}

double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

void put_word(std::uint64_t word, std::string& bytes) {
  bytes.append(reinterpret_cast<const char*>(&word), sizeof word);
}

// The directory's entry of a new file survives a crash only once the directory is flushed.
void sync_directory(const std::filesystem::path& file) {
  const int fd =
      ::open(file.parent_path().empty() ? "." : file.parent_path().c_str(), O_RDONLY | O_DIRECTORY);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}

}  // namespace

RunJournal::RunJournal(std::filesystem::path path, int fd) : path_(std::move(path)), fd_(fd) {
  last_sync_s_ = now_s();
}

RunJournal::RunJournal(std::filesystem::path path, const std::string& identity,
                       const std::vector<InputStamp>& inputs)
    : path_(std::move(path)) {
  fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) throw run_error(path_.string(), std::string("cannot create: ") + strerror(errno));
  std::string header;
  put_word(kMagic, header);
  put_word(fnv1a(identity.data(), identity.size()), header);
  std::string stamps;
  encode_stamps(inputs, stamps);
  put_word(stamps.size(), header);
  header += stamps;
  write_all(header.data(), header.size());
  sync();
  sync_directory(path_);
}

RunJournal::~RunJournal() {
  if (fd_ >= 0) ::close(fd_);
}

void RunJournal::write_all(const char* bytes, std::size_t size) {
  std::size_t done = 0;
  while (done < size) {
    const ssize_t n = ::write(fd_, bytes + done, size - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw write_error(path_.string(), n < 0 ? errno : ENOSPC);
    done += static_cast<std::size_t>(n);
  }
}

void RunJournal::append(std::span<const ShotRecord> records, std::int64_t ray_queries) {
  // A frame holds at most kFrameBytes of records, which LZ4 takes at once; the batch's ray
  // queries go with its last frame.
  raw_.clear();
  std::size_t in_frame = 0;
  for (std::size_t i = 0; i < records.size(); ++i) {
    encode_record(records[i], raw_);
    ++in_frame;
    const bool last = i + 1 == records.size();
    if (last || raw_.size() >= kFrameBytes) {
      write_frame(raw_, in_frame, last ? ray_queries : 0);
      records_ += in_frame;
      raw_.clear();
      in_frame = 0;
    }
  }
  if (records.empty()) write_frame(raw_, 0, ray_queries);
  if (now_s() - last_sync_s_ >= kSyncInterval_s) sync();
}

void RunJournal::write_frame(const std::string& raw, std::size_t records,
                             std::int64_t ray_queries) {
  // LZ4 rather than deflate: as small within 7 % (half the records' bytes: Monte Carlo weights
  // repeat), 25 times faster (deflate's fastest level was a fifth of a bare slope's CPU).
  if (raw.size() > kLargestFrame)
    throw run_error(path_.string(), "a shot's record is too large for the journal (" +
                                        std::to_string(raw.size()) + " bytes)");
  // The frame is built in place in a buffer kept from frame to frame: a new one each time cost
  // its page faults and zeroing, more than LZ4 itself.
  // marker, first record, records, queries, sizes
  constexpr std::size_t kHeader = 6 * sizeof(std::uint64_t);
  const auto bound = static_cast<std::size_t>(LZ4_compressBound(static_cast<int>(raw.size())));
  if (frame_.size() < kHeader + bound + sizeof(std::uint64_t))
    frame_.resize(kHeader + bound + sizeof(std::uint64_t));
  const int size = LZ4_compress_default(raw.data(), frame_.data() + kHeader,
                                        static_cast<int>(raw.size()), static_cast<int>(bound));
  if (size <= 0) throw run_error(path_.string(), "cannot compress the journal's records");
  const std::array<std::uint64_t, 6> words = {kFrameMarker,
                                              records_,
                                              records,
                                              static_cast<std::uint64_t>(ray_queries),
                                              static_cast<std::uint64_t>(size),
                                              raw.size()};
  std::memcpy(frame_.data(), words.data(), kHeader);
  const std::size_t checked = kHeader + static_cast<std::size_t>(size);
  const std::uint64_t checksum = fnv1a(frame_.data(), checked);
  std::memcpy(frame_.data() + checked, &checksum, sizeof checksum);
  write_all(frame_.data(), checked + sizeof checksum);
}

void RunJournal::sync() {
  if (::fsync(fd_) != 0) throw write_error(path_.string(), errno);
  last_sync_s_ = now_s();
}

void RunJournal::remove() {
  ::close(fd_);
  fd_ = -1;
  std::error_code ignored;
  std::filesystem::remove(path_, ignored);
}

namespace {

// The journal's header, checked against this version, this run's identity and its input files
// now: false when it is not whole (killed before it was). `header_bytes` receives its length.
bool read_header(std::ifstream& in, const std::filesystem::path& path, std::uint64_t file_bytes,
                 const std::string& identity, const std::vector<InputStamp>& inputs,
                 std::uint64_t& header_bytes) {
  std::array<std::uint64_t, 3> header{};
  if (!in.read(reinterpret_cast<char*>(header.data()), sizeof header)) return false;
  // "GWJRNL" and two digits: the digits say the format.
  constexpr std::uint64_t kMagicName = 0xffffffffffff;
  if ((header[0] & kMagicName) == (kMagic & kMagicName) && header[0] != kMagic)
    throw config_error(path.string(),
                       "a run journal of another glaswave version, which this one cannot resume; "
                       "remove the output directory");
  if (header[0] != kMagic)
    throw config_error(path.string(), "not a glaswave run journal; remove the output directory");
  if (header[1] != fnv1a(identity.data(), identity.size()))
    throw config_error(path.parent_path().string(),
                       "the interrupted run there was made with another configuration, --set, "
                       "--seed or --shots (or another glaswave version): --resume must repeat "
                       "its command; or remove the directory");
  // The stamps' length is checked against the file before it is allocated.
  if (header[2] > file_bytes - sizeof header) return false;
  std::string bytes(header[2], '\0');
  if (!in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()))) return false;
  std::vector<InputStamp> journalled;
  if (!decode_stamps(bytes, journalled)) return false;
  require_unchanged_inputs(journalled, inputs);
  header_bytes = sizeof header + header[2];
  return true;
}

// The next whole frame (its words, and its bytes with them in `frame`); false at the end or at
// a torn frame. `file_bytes` is the journal's size: a payload said to be longer than what is
// left of the file is torn, and is not allocated (a damaged size word asked for 2 GB).
bool read_frame(std::ifstream& in, std::uint64_t file_bytes, std::array<std::uint64_t, 6>& words,
                std::string& frame) {
  if (!in.read(reinterpret_cast<char*>(words.data()), sizeof words)) return false;
  const auto at = static_cast<std::uint64_t>(in.tellg());
  const std::uint64_t left = at <= file_bytes ? file_bytes - at : 0;
  // Sizes beyond what LZ4 takes, or beyond the file: not a whole frame.
  if (words[0] != kFrameMarker ||
      words[4] > static_cast<std::uint64_t>(LZ4_COMPRESSBOUND(kLargestFrame)) ||
      words[5] > kLargestFrame || left < sizeof(std::uint64_t) ||
      words[4] > left - sizeof(std::uint64_t))
    return false;
  frame.assign(reinterpret_cast<const char*>(words.data()), sizeof words);
  frame.resize(sizeof words + words[4] + sizeof(std::uint64_t));
  if (!in.read(frame.data() + sizeof words,
               static_cast<std::streamsize>(frame.size() - sizeof words)))
    return false;
  std::uint64_t checksum = 0;
  std::memcpy(&checksum, frame.data() + frame.size() - sizeof checksum, sizeof checksum);
  return checksum == fnv1a(frame.data(), frame.size() - sizeof checksum);  // else torn
}

}  // namespace

std::unique_ptr<RunJournal> RunJournal::resume(
    const std::filesystem::path& path, const std::string& identity,
    const std::function<void(const ShotRecord&)>& consume, std::int64_t& ray_queries,
    const std::vector<InputStamp>& inputs) {
  ray_queries = 0;
  // A journal replaced by a FIFO would be waited on for ever.
  require_input_file(path.native(), "the run journal", ErrorKind::config);
  std::error_code size_error;
  const std::uint64_t file_bytes = std::filesystem::file_size(path, size_error);
  if (size_error) throw run_error(path.string(), "cannot read its size: " + size_error.message());
  std::ifstream in(path, std::ios::binary);
  // A journal killed before its header was whole holds no shot: begin it again.
  std::uint64_t valid_end = 0;
  if (file_bytes < 3 * sizeof(std::uint64_t) ||
      !read_header(in, path, file_bytes, identity, inputs, valid_end))
    return std::make_unique<RunJournal>(path, identity, inputs);
  std::uint64_t records = 0;  // handed on so far: the index the next frame must begin at
  std::string frame, raw;
  for (std::uint64_t number = 0;; ++number) {
    // marker, first record, records, ray queries, sizes
    std::array<std::uint64_t, 6> words{};
    if (!read_frame(in, file_bytes, words, frame)) break;
    // A whole frame out of its place (a frame repeated, one lost, frames swapped) is not a
    // torn end: the journal no longer says which shots were done, and resuming would double
    // some and lose others.
    if (words[1] != records)
      throw config_error(path.string(),
                         "frame " + std::to_string(number + 1) + " holds records from " +
                             std::to_string(words[1]) + " where " + std::to_string(records) +
                             " was due (frames repeated, missing or out of order): the journal "
                             "does not describe one run; remove the output directory");
    raw.resize(words[5]);
    if (LZ4_decompress_safe(frame.data() + sizeof words, raw.data(), static_cast<int>(words[4]),
                            static_cast<int>(raw.size())) != static_cast<int>(raw.size()))
      break;
    std::size_t offset = 0;
    for (std::uint64_t i = 0; i < words[2]; ++i) consume(decode_record(raw, offset));
    records += words[2];
    ray_queries += static_cast<std::int64_t>(words[3]);
    valid_end += frame.size();
  }
  in.close();
  // A torn last frame goes: what comes next is appended after the last whole one.
  const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
  if (fd < 0) throw run_error(path.string(), std::string("cannot open: ") + strerror(errno));
  if (::ftruncate(fd, static_cast<off_t>(valid_end)) != 0 || ::lseek(fd, 0, SEEK_END) < 0) {
    const int error_number = errno;
    ::close(fd);
    throw write_error(path.string(), error_number);
  }
  std::unique_ptr<RunJournal> journal(new RunJournal(path, fd));
  journal->records_ = records;
  return journal;
}

}  // namespace glaswave
