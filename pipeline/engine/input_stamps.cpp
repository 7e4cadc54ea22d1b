// Input files stamped for --resume: which files a run reads, their size, time and a hash.
#include "pipeline/engine/input_stamps.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/input_file.hpp"
#include "pipeline/config/config.hpp"

namespace glaswave {
namespace {

namespace fs = std::filesystem;

constexpr std::uint64_t kPrime1 = 0x9e3779b185ebca87;
constexpr std::uint64_t kPrime2 = 0xc2b2ae3d27d4eb4f;

std::uint64_t rotl(std::uint64_t x, int r) { return (x << r) | (x >> (64 - r)); }

std::uint64_t load_word(const unsigned char* p) {
  std::uint64_t w = 0;
  std::memcpy(&w, p, sizeof w);
  return w;
}

void add_file(const std::string& path, std::vector<std::string>& files) {
  if (path.empty()) return;
  std::error_code error;
  if (fs::is_directory(path, error)) {
    // A folder given as a layer (a Shapefile's): the files in it.
    std::vector<std::string> inside;
    for (const auto& entry : fs::directory_iterator(path, error))
      if (entry.is_regular_file(error)) inside.push_back(entry.path().string());
    std::sort(inside.begin(), inside.end());
    for (const std::string& file : inside) add_file(file, files);
    return;
  }
  if (std::find(files.begin(), files.end(), path) == files.end()) files.push_back(path);
  // A Shapefile's attributes, index and CRS are files beside it.
  const fs::path file(path);
  if (file.extension() == ".shp" || file.extension() == ".SHP")
    for (const char* extension : {".dbf", ".shx", ".prj", ".DBF", ".SHX", ".PRJ"}) {
      const fs::path sibling = fs::path(file).replace_extension(extension);
      if (fs::is_regular_file(sibling, error) &&
          std::find(files.begin(), files.end(), sibling.string()) == files.end())
        files.push_back(sibling.string());
    }
}

std::string describe_time(std::int64_t ns) {
  const std::time_t seconds = static_cast<std::time_t>(ns / 1000000000);
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

void put_word(std::uint64_t word, std::string& bytes) {
  bytes.append(reinterpret_cast<const char*>(&word), sizeof word);
}

bool get_word(const std::string& bytes, std::size_t& at, std::uint64_t& word) {
  if (bytes.size() - at < sizeof word) return false;
  std::memcpy(&word, bytes.data() + at, sizeof word);
  at += sizeof word;
  return true;
}

}  // namespace

std::vector<std::string> run_input_files(const Config& config) {
  std::vector<std::string> files;
  add_file(config.terrain.dem, files);
  if (config.canopy) {
    const CanopySettings& c = *config.canopy;
    add_file(c.crowns_file, files);
    add_file(c.stands, files);
    for (const StandArea& stand : c.stand_areas) add_file(stand.canopy.crowns_file, files);
    add_file(c.voxels_file, files);
    add_file(c.point_cloud_file, files);
    add_file(c.facet_trees_file, files);
    for (const auto& model : c.facet_models) add_file(model.second, files);
  }
  add_file(config.track.ephemeris, files);
  add_file(config.track.granule, files);
  return files;
}

void ContentHash::round(const unsigned char* block) {
  for (int lane = 0; lane < 4; ++lane) {
    std::uint64_t& h = lanes_[lane];
    h = rotl(h + load_word(block + 8 * lane) * kPrime2, 31) * kPrime1;
  }
}

void ContentHash::update(const char* data, std::size_t size) {
  const auto* p = reinterpret_cast<const unsigned char*>(data);
  total_ += size;
  if (tail_size_ > 0) {
    const std::size_t take = std::min(size, sizeof tail_ - tail_size_);
    std::memcpy(tail_ + tail_size_, p, take);
    tail_size_ += take;
    p += take;
    size -= take;
    if (tail_size_ < sizeof tail_) return;
    round(tail_);
    tail_size_ = 0;
  }
  for (; size >= sizeof tail_; p += sizeof tail_, size -= sizeof tail_) round(p);
  std::memcpy(tail_, p, size);
  tail_size_ = size;
}

std::uint64_t ContentHash::digest() const {
  std::uint64_t h = total_ * kPrime1;
  for (std::uint64_t lane : lanes_) h = rotl(h ^ (lane * kPrime2), 27) * kPrime1 + kPrime2;
  // The last bytes, one at a time: a short file is still told from its neighbours.
  for (std::size_t i = 0; i < tail_size_; ++i) h = rotl(h ^ (tail_[i] * kPrime1), 11) * kPrime2;
  h ^= h >> 33;
  h *= kPrime2;
  h ^= h >> 29;
  return h;
}

InputStamp stamp_input_file(const std::string& path) {
  // A FIFO or a device would be read for ever.
  require_input_file(path, "an input file of the run");
  InputStamp stamp;
  stamp.path = path;
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw input_error(path, std::string("cannot read it: ") + std::strerror(errno));
  struct stat info {};
  if (::fstat(fd, &info) != 0) {
    const int error_number = errno;
    ::close(fd);
    throw input_error(path, std::string("cannot read it: ") + std::strerror(error_number));
  }
  stamp.size_bytes = static_cast<std::uint64_t>(info.st_size);
  stamp.mtime_ns = static_cast<std::int64_t>(info.st_mtim.tv_sec) * 1000000000 +
                   static_cast<std::int64_t>(info.st_mtim.tv_nsec);
  ContentHash hash;
  std::vector<char> buffer(std::size_t{1} << 20);
  for (;;) {
    const ssize_t n = ::read(fd, buffer.data(), buffer.size());
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int error_number = errno;
      ::close(fd);
      throw input_error(path, std::string("cannot read it: ") + std::strerror(error_number));
    }
    if (n == 0) break;
    hash.update(buffer.data(), static_cast<std::size_t>(n));
  }
  ::close(fd);
  stamp.hash = hash.digest();
  return stamp;
}

std::vector<InputStamp> stamp_input_files(const std::vector<std::string>& paths) {
  std::vector<InputStamp> stamps;
  stamps.reserve(paths.size());
  for (const std::string& path : paths) stamps.push_back(stamp_input_file(path));
  return stamps;
}

void require_unchanged_inputs(const std::vector<InputStamp>& journalled,
                              const std::vector<InputStamp>& now) {
  const std::string advice =
      ": --resume would write products half from the old file and half from the new; restore "
      "the file, or run again into a new output directory";
  for (const InputStamp& stamp : now) {
    const auto was = std::find_if(journalled.begin(), journalled.end(),
                                  [&](const InputStamp& s) { return s.path == stamp.path; });
    if (was == journalled.end())
      throw config_error(stamp.path, "not an input of the interrupted run" + advice);
    if (was->size_bytes != stamp.size_bytes)
      throw config_error(stamp.path, "changed since the interrupted run began (" +
                                         std::to_string(stamp.size_bytes) + " bytes, were " +
                                         std::to_string(was->size_bytes) + ")" + advice);
    // The same size and bits with another time (touched, copied back) give the same products.
    if (was->hash != stamp.hash)
      throw config_error(stamp.path,
                         "changed since the interrupted run began (its content: "
                         "modified " +
                             describe_time(stamp.mtime_ns) + ", was " +
                             describe_time(was->mtime_ns) + ")" + advice);
  }
  for (const InputStamp& stamp : journalled)
    if (std::none_of(now.begin(), now.end(),
                     [&](const InputStamp& s) { return s.path == stamp.path; }))
      throw config_error(stamp.path, "an input of the interrupted run, gone" + advice);
}

void encode_stamps(const std::vector<InputStamp>& stamps, std::string& bytes) {
  put_word(stamps.size(), bytes);
  for (const InputStamp& s : stamps) {
    put_word(s.path.size(), bytes);
    bytes += s.path;
    put_word(s.size_bytes, bytes);
    put_word(static_cast<std::uint64_t>(s.mtime_ns), bytes);
    put_word(s.hash, bytes);
  }
}

bool decode_stamps(const std::string& bytes, std::vector<InputStamp>& stamps) {
  std::size_t at = 0;
  std::uint64_t count = 0;
  if (!get_word(bytes, at, count)) return false;
  stamps.clear();
  for (std::uint64_t i = 0; i < count; ++i) {
    InputStamp s;
    std::uint64_t length = 0, mtime = 0;
    if (!get_word(bytes, at, length) || bytes.size() - at < length) return false;
    s.path = bytes.substr(at, length);
    at += length;
    if (!get_word(bytes, at, s.size_bytes) || !get_word(bytes, at, mtime) ||
        !get_word(bytes, at, s.hash))
      return false;
    s.mtime_ns = static_cast<std::int64_t>(mtime);
    stamps.push_back(std::move(s));
  }
  return at == bytes.size();
}

}  // namespace glaswave
