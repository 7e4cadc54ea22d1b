// Reader programs started with posix_spawn and their messages over a socket pair.
#include "core/spawned_reader.hpp"

#include <dlfcn.h>
#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <mutex>
#include <stdexcept>
#include <system_error>
#include <thread>

#include "core/netcdf_lock.hpp"

extern char** environ;

namespace glaswave {
namespace {

class SpawnActions {
 public:
  SpawnActions() { ok_ = posix_spawn_file_actions_init(&actions_) == 0; }
  ~SpawnActions() {
    if (ok_) posix_spawn_file_actions_destroy(&actions_);
  }
  bool ok() const { return ok_; }
  posix_spawn_file_actions_t* get() { return &actions_; }

 private:
  posix_spawn_file_actions_t actions_;
  bool ok_ = false;
};

// SIGXCPU at its default, ending the program, and no signal blocked: a caller ignoring or
// blocking it would hand that on through exec, and a reader spinning inside HDF5 would spin on.
class SpawnAttributes {
 public:
  SpawnAttributes() {
    if (posix_spawnattr_init(&attributes_) != 0) return;
    made_ = true;
    sigset_t defaults, none;
    ok_ =
        sigemptyset(&defaults) == 0 && sigaddset(&defaults, SIGXCPU) == 0 &&
        sigemptyset(&none) == 0 && posix_spawnattr_setsigdefault(&attributes_, &defaults) == 0 &&
        posix_spawnattr_setsigmask(&attributes_, &none) == 0 &&
        posix_spawnattr_setflags(&attributes_, POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETSIGMASK) == 0;
  }
  ~SpawnAttributes() {
    if (made_) posix_spawnattr_destroy(&attributes_);
  }
  bool ok() const { return ok_; }
  const posix_spawnattr_t* get() const { return &attributes_; }

 private:
  posix_spawnattr_t attributes_;
  bool made_ = false, ok_ = false;
};

std::uint64_t file_bytes(const char* file) {
  std::error_code error;
  const std::uintmax_t size = std::filesystem::file_size(file, error);
  return error ? 0 : size;
}

// Reads `size` bytes whole; false at the end of input or an error first.
bool read_whole(int fd, void* out, std::size_t size) {
  auto* at = static_cast<char*>(out);
  while (size > 0) {
    const ssize_t n = ::read(fd, at, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    at += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

// The longest message a reader sends: a voxel grid's largest window (2^28 voxels of 4 bytes) or a
// granule's shots, with room to spare. A longer length is a reader gone wrong.
constexpr std::uint64_t kLongestMessage = std::uint64_t{1} << 36;

}  // namespace

double cpu_seconds(const rusage& used) {
  const auto seconds = [](const timeval& t) {
    return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_usec) * 1e-6;
  };
  return seconds(used.ru_utime) + seconds(used.ru_stime);
}

double reader_cpu_budget_s(std::uint64_t bytes) {
  // Measured (glaswave-read-voxels, 2000 x 2000 x 30 grids of random PAD, 458 MiB of floats):
  // opening takes 0.1 s; a block of 64 x 64 columns 0.02 s, 2.5 s where each layer is one chunk
  // (371 MiB file: every chunk inflated for every block); the whole grid in one window 1.9 s
  // (uncompressed, 458 MiB), 4.5 s (zlib, 385 MiB), 3.6 s (zeros, 1 MiB). glaswave-read-granule:
  // the limit's 5 million shots (267 MiB answered) 2.3 s (539 MiB), 2.9 s (gzip, 365 MiB), 2.5 s
  // (gzip of one position, 0.8 MB). So at most 9.4 ms of CPU a MiB read and answered, against
  // 62.5 ms here (6.6 times), and 0.1 s to open against 1 s; a fuzz input of a few kB is ended
  // after 1 s (3.3 s of CPU took over 10 s of wall at a load of 7 on 2 cores: libFuzzer times out).
  return kReaderBaseCpuS + static_cast<double>(bytes) / kReaderBytesPerCpuS;
}

std::filesystem::path find_reader_program(const std::string& name,
                                          const std::vector<std::filesystem::path>& also) {
  namespace fs = std::filesystem;
  std::vector<fs::path> places;
  Dl_info self{};
  if (::dladdr(reinterpret_cast<void*>(&find_reader_program), &self) != 0 && self.dli_fname) {
    std::error_code error;
    const fs::path binary = fs::canonical(self.dli_fname, error);
    if (!error) {
      const fs::path folder = binary.parent_path();
      places = {folder / name, folder / "bin" / name,
                folder / ".." / "libexec" / "glaswave" / name};
    }
  }
  places.insert(places.end(), also.begin(), also.end());
  for (const fs::path& place : places) {
    std::error_code error;
    if (fs::is_regular_file(place, error) && ::access(place.c_str(), X_OK) == 0) return place;
  }
  return {};
}

SpawnedReader::SpawnedReader(const std::filesystem::path& program,
                             const std::vector<std::string>& arguments, std::string file,
                             std::string what, std::string hello)
    : program_(program), file_(std::move(file)), what_(std::move(what)), hello_(std::move(hello)) {
  const std::string cannot = "cannot read " + what_ + ": ";
  // Both ends close on exec: another thread's child never holds the reader's end open.
  int ends[2] = {-1, -1};
  if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, ends) != 0)
    throw run_error(file_, cannot + "no socket to its reader (" + std::strerror(errno) + ")");
  socket_ = ends[0];
  SpawnActions actions;
  const SpawnAttributes attributes;
  // Nothing else of the caller's goes with it: a file another thread has open through HDF5 holds
  // HDF5's flock, and a reader holding a copy kept the lock after that thread closed the file,
  // so that opening it again failed ("NetCDF: HDF error" on the shots.nc of another thread's run).
  if (!actions.ok() || !attributes.ok() ||
      posix_spawn_file_actions_adddup2(actions.get(), ends[1], STDIN_FILENO) != 0 ||
      posix_spawn_file_actions_adddup2(actions.get(), ends[1], STDOUT_FILENO) != 0 ||
      posix_spawn_file_actions_addclosefrom_np(actions.get(), STDERR_FILENO + 1) != 0) {
    ::close(ends[0]);
    ::close(ends[1]);
    throw run_error(file_, cannot + "cannot start its reader");
  }
  std::vector<std::string> words{program.string()};
  words.insert(words.end(), arguments.begin(), arguments.end());
  std::vector<char*> argv;
  for (std::string& word : words) argv.push_back(word.data());
  argv.push_back(nullptr);
  // Started under the HDF5 lock: until it has run, the reader holds a copy of every descriptor,
  // and a file another thread's HDF5 closed meanwhile would stay locked (see above); posix_spawn
  // returns once the copies are closed and the program runs.
  int error = 0;
  {
    const std::lock_guard lock(netcdf_library_mutex());
    error = posix_spawn(&child_, argv[0], actions.get(), attributes.get(), argv.data(), environ);
  }
  ::close(ends[1]);
  if (error != 0) {
    ::close(ends[0]);
    child_ = -1;
    throw run_error(
        file_, cannot + "cannot start " + program.string() + " (" + std::strerror(error) + ")");
  }
}

SpawnedReader::~SpawnedReader() {
  hang_up();  // the program reads the end of its input and ends
  wait();
}

void SpawnedReader::hang_up() {
  if (socket_ < 0) return;
  // shutdown, not only close: a copy of this end in a process forked meanwhile (Python's
  // multiprocessing) would keep the program waiting for more, and wait() with it.
  ::shutdown(socket_, SHUT_RDWR);
  ::close(socket_);
  socket_ = -1;
}

void SpawnedReader::wait() {
  if (child_ < 0) return;
  int status = 0;
  rusage used{};
  pid_t waited = -1;
  while ((waited = ::wait4(child_, &status, 0, &used)) < 0 && errno == EINTR) {
  }
  child_ = -1;
  // A caller ignoring SIGCHLD has its children reaped unasked (ECHILD): the messages alone decide.
  if (waited < 0 || !failure_.empty()) return;
  const std::string refused = "HDF5 failed reading " + what_ + " (a corrupt file): it is refused";
  if (WIFSIGNALED(status) && WTERMSIG(status) == SIGXCPU) {
    // The rule, not one number: the program alone knows what a request asked it to answer.
    char budget[160];
    std::snprintf(budget, sizeof budget,
                  "(%g s, and 1 s for each %g MiB of the file and of its answer; %.1f s of CPU "
                  "in all)",
                  kReaderBaseCpuS, kReaderBytesPerCpuS / (1 << 20), cpu_seconds(used));
    failure_ = "reading " + what_ + " took its reader program, " + program_.filename().string() +
               ", past its CPU budget on one request " + budget +
               ", so the file may be corrupt: it is refused";
  } else if (WIFSIGNALED(status))
    failure_ = refused + " (its reader, " + program_.string() + ", ended by signal " +
               std::to_string(WTERMSIG(status)) + ")";
  else if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    failure_ = refused;
}

void SpawnedReader::ended(const std::string& why) {
  if (failure_.empty()) {
    hang_up();
    wait();
  }
  if (failure_.empty())
    failure_ =
        "HDF5 failed reading " + what_ + " (a corrupt file): it is " + "refused (" + why + ")";
  throw input_error(file_, failure_);
}

void SpawnedReader::send(std::string_view message) {
  if (!failure_.empty() || socket_ < 0) ended("its reader has ended");
  const std::uint64_t size = message.size();
  std::string bytes(reinterpret_cast<const char*>(&size), sizeof size);
  bytes += message;
  std::size_t sent = 0;
  while (sent < bytes.size()) {
    // MSG_NOSIGNAL: a reader that has crashed is an error here, not a SIGPIPE ending the caller.
    const ssize_t n = ::send(socket_, bytes.data() + sent, bytes.size() - sent, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) ended("its reader stopped reading");
    sent += static_cast<std::size_t>(n);
  }
}

std::string SpawnedReader::receive() {
  if (!failure_.empty() || socket_ < 0) ended("its reader has ended");
  if (!greeted_) {
    std::string hello(hello_.size(), '\0');
    if (!read_whole(socket_, hello.data(), hello.size())) ended("its reader said nothing");
    if (hello != hello_)
      throw run_error(file_, "cannot read " + what_ + ": " + program_.string() +
                                 " is not the reader of this glaswave (another version?)");
    greeted_ = true;
  }
  std::uint64_t size = 0;
  if (!read_whole(socket_, &size, sizeof size)) ended("its reader's reply is cut");
  if (size > kLongestMessage) ended("its reader's reply is too long");
  std::string message;
  message.reserve(std::min<std::uint64_t>(size, std::uint64_t{1} << 26));
  while (message.size() < size) {
    const std::size_t had = message.size();
    const std::size_t part = std::min<std::uint64_t>(size - had, std::uint64_t{1} << 24);
    message.resize(had + part);
    if (!read_whole(socket_, message.data() + had, part)) ended("its reader's reply is cut");
  }
  return message;
}

void SpawnedReader::finish() {
  hang_up();
  wait();
  if (!failure_.empty()) throw input_error(file_, failure_);
}

int take_reply_channel() {
  // A reader outlives no caller: one that HDF5 sent spinning on a corrupt file (voxel_fuzzer
  // found one) would run on after its caller ended (a killed run, a fuzzer's timeout), holding
  // its caller's pipes. Reparented, it ends; the watchdog calls nothing of HDF5's.
  const pid_t caller = ::getppid();
  std::thread([caller] {
    for (;;) {
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
      if (::getppid() != caller) ::_exit(2);
    }
  }).detach();
  const int channel = ::fcntl(STDOUT_FILENO, F_DUPFD_CLOEXEC, STDERR_FILENO + 1);
  if (channel >= 0) ::dup2(STDERR_FILENO, STDOUT_FILENO);
  return channel;
}

void bound_request_cpu(const char* file, std::uint64_t answer_bytes) {
  const double budget_s = reader_cpu_budget_s(file_bytes(file) + answer_bytes);
  rusage used{};
  rlimit limit{};
  if (::getrusage(RUSAGE_SELF, &used) != 0 || ::getrlimit(RLIMIT_CPU, &limit) != 0) return;
  // Whole seconds, rounded up: the request has its budget at least.
  auto soft = static_cast<rlim_t>(std::ceil(cpu_seconds(used) + budget_s));
  // Raised to the hard limit at most; a second short of it, since at the hard limit the kernel
  // sends SIGKILL, which would not say why.
  if (limit.rlim_max != RLIM_INFINITY)
    soft = std::min(soft, limit.rlim_max - std::min<rlim_t>(limit.rlim_max, 1));
  limit.rlim_cur = soft;
  ::setrlimit(RLIMIT_CPU, &limit);
}

bool read_message(int fd, std::string& message) {
  std::uint64_t size = 0;
  if (!read_whole(fd, &size, sizeof size) || size > kLongestMessage) return false;
  message.assign(size, '\0');
  return read_whole(fd, message.data(), message.size());
}

bool write_message(int fd, std::string_view message) {
  const std::uint64_t size = message.size();
  return write_hello(fd, std::string_view(reinterpret_cast<const char*>(&size), sizeof size)) &&
         write_hello(fd, message);
}

bool write_hello(int fd, std::string_view bytes) {
  std::size_t sent = 0;
  while (sent < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + sent, bytes.size() - sent);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    sent += static_cast<std::size_t>(n);
  }
  return true;
}

void MessageOut::put_error(const Error& error) {
  put(static_cast<std::int32_t>(error.kind()));
  put_string(error.place());
  put_string(error.message());
}

void MessageIn::get_bytes(void* out, std::size_t size) {
  if (text_.size() - at_ < size) throw std::length_error("a reader's message is cut");
  std::memcpy(out, text_.data() + at_, size);
  at_ += size;
}

std::string MessageIn::get_string() {
  const auto size = get<std::uint64_t>();
  if (text_.size() - at_ < size) throw std::length_error("a reader's message is cut");
  std::string text = text_.substr(at_, size);
  at_ += size;
  return text;
}

Error MessageIn::get_error() {
  const auto kind = get<std::int32_t>();
  std::string place = get_string();
  const std::string message = get_string();
  const ErrorKind known = kind == static_cast<std::int32_t>(ErrorKind::config) ? ErrorKind::config
                          : kind == static_cast<std::int32_t>(ErrorKind::run)  ? ErrorKind::run
                                                                               : ErrorKind::input;
  return Error(known, std::move(place), message);
}

}  // namespace glaswave
