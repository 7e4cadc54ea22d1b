// The run journal on disk: a 16-byte header (magic, identity hash), then frames: a marker, the
// record count, the ray queries, the payload's size and its size uncompressed, the payload
// (records as record_codec writes them, deflated: waveforms are mostly zeros) and an FNV-1a
// checksum of all that. Written with POSIX calls so that every
// write and flush is checked.
#include "pipeline/engine/journal.hpp"

#include <fcntl.h>
#include <unistd.h>
#include <zlib.h>

#include <array>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <fstream>
#include <vector>

#include "core/error.hpp"
#include "core/write_error.hpp"
#include "pipeline/products/record_codec.hpp"

namespace glaswave {
namespace {

constexpr std::uint64_t kMagic = 0x32304c4e524a5747;  // "GWJRNL02"
constexpr std::uint64_t kFrameMarker = 0x454d415246574721;
// A run's longest wait between flushes of the journal to the disk.
constexpr double kSyncInterval_s = 1.0;

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

RunJournal::RunJournal(std::filesystem::path path, const std::string& identity)
    : path_(std::move(path)) {
  fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) throw run_error(path_.string(), std::string("cannot create: ") + strerror(errno));
  std::string header;
  put_word(kMagic, header);
  put_word(fnv1a(identity.data(), identity.size()), header);
  write_all(header);
  sync();
  sync_directory(path_);
}

RunJournal::~RunJournal() {
  if (fd_ >= 0) ::close(fd_);
}

void RunJournal::write_all(const std::string& bytes) {
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw write_error(path_.string(), n < 0 ? errno : ENOSPC);
    done += static_cast<std::size_t>(n);
  }
}

void RunJournal::append(std::span<const ShotRecord> records, std::int64_t ray_queries) {
  std::string raw;
  for (const ShotRecord& record : records) encode_record(record, raw);
  // Deflate's fastest level: a few times smaller, at a small part of a shot's cost.
  uLongf size = compressBound(raw.size());
  std::string payload(size, '\0');
  if (compress2(reinterpret_cast<Bytef*>(payload.data()), &size,
                reinterpret_cast<const Bytef*>(raw.data()), raw.size(), 1) != Z_OK)
    throw run_error(path_.string(), "cannot compress the journal's records");
  payload.resize(size);
  std::string frame;
  put_word(kFrameMarker, frame);
  put_word(records.size(), frame);
  put_word(static_cast<std::uint64_t>(ray_queries), frame);
  put_word(payload.size(), frame);
  put_word(raw.size(), frame);
  frame += payload;
  put_word(fnv1a(frame.data(), frame.size()), frame);
  write_all(frame);
  if (now_s() - last_sync_s_ >= kSyncInterval_s) sync();
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

std::unique_ptr<RunJournal> RunJournal::resume(
    const std::filesystem::path& path, const std::string& identity,
    const std::function<void(const ShotRecord&)>& consume, std::int64_t& ray_queries) {
  ray_queries = 0;
  std::ifstream in(path, std::ios::binary);
  std::array<std::uint64_t, 2> header{};
  // A journal killed before its header was whole holds no shot: begin it again.
  if (!in.read(reinterpret_cast<char*>(header.data()), sizeof header))
    return std::make_unique<RunJournal>(path, identity);
  if (header[0] != kMagic)
    throw config_error(path.string(), "not a glaswave run journal; remove the output directory");
  if (header[1] != fnv1a(identity.data(), identity.size()))
    throw config_error(path.parent_path().string(),
                       "the interrupted run there was made with another configuration, --set, "
                       "--seed or --shots (or another glaswave version): --resume must repeat "
                       "its command; or remove the directory");
  std::uint64_t valid_end = sizeof header;
  std::string frame, raw;
  for (;;) {
    std::array<std::uint64_t, 5> words{};  // marker, records, ray queries, sizes
    if (!in.read(reinterpret_cast<char*>(words.data()), sizeof words)) break;
    constexpr std::uint64_t kLargest = std::uint64_t{1} << 40;  // beyond: not a frame
    if (words[0] != kFrameMarker || words[3] > kLargest || words[4] > kLargest) break;
    frame.assign(reinterpret_cast<const char*>(words.data()), sizeof words);
    frame.resize(sizeof words + words[3] + sizeof(std::uint64_t));
    if (!in.read(frame.data() + sizeof words,
                 static_cast<std::streamsize>(frame.size() - sizeof words)))
      break;
    std::uint64_t checksum = 0;
    std::memcpy(&checksum, frame.data() + frame.size() - sizeof checksum, sizeof checksum);
    if (checksum != fnv1a(frame.data(), frame.size() - sizeof checksum)) break;  // torn
    raw.resize(words[4]);
    uLongf size = raw.size();
    if (uncompress(reinterpret_cast<Bytef*>(raw.data()), &size,
                   reinterpret_cast<const Bytef*>(frame.data() + sizeof words), words[3]) != Z_OK ||
        size != raw.size())
      break;
    std::size_t offset = 0;
    for (std::uint64_t i = 0; i < words[1]; ++i) consume(decode_record(raw, offset));
    ray_queries += static_cast<std::int64_t>(words[2]);
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
  return std::unique_ptr<RunJournal>(new RunJournal(path, fd));
}

}  // namespace glaswave
