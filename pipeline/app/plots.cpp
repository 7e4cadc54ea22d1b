// write_plots: runs the matplotlib script as a child process (posix_spawn with an argument
// vector, so no shell sees the paths) and turns its failure into a one-line Error, the whole of
// its stderr in plots.log.
#include "pipeline/app/plots.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <fstream>
#include <mutex>
#include <string>
#include <system_error>
#include <vector>

#include "core/error.hpp"
#include "core/netcdf_lock.hpp"

extern char** environ;

namespace glaswave {
namespace {

namespace fs = std::filesystem;

// Enough of a Python traceback to see where it failed, without flooding the message.
constexpr std::size_t kMaxStderrChars = 4000;
// The part of it in the one-line message.
constexpr std::size_t kMaxMessageChars = 300;

std::string describe_errno(int error) { return std::generic_category().message(error); }

// GLASWAVE_SHARE when set; else share/glaswave beside the installed command (P/bin/glaswave ->
// P/share/glaswave) when it holds the scripts; else the source tree the command was built from.
fs::path share_dir() {
  const char* env = std::getenv("GLASWAVE_SHARE");
  if (env != nullptr && *env != '\0') return env;
  std::error_code error;
  const fs::path executable = fs::read_symlink("/proc/self/exe", error);
  if (!error) {
    const fs::path installed = executable.parent_path().parent_path() / "share" / "glaswave";
    if (fs::is_regular_file(installed / "plots" / "plot_products.py", error)) return installed;
  }
  return GLASWAVE_SHARE_DIR;
}

// A file descriptor closed when its owner goes.
class Fd {
 public:
  explicit Fd(int fd = -1) : fd_(fd) {}
  ~Fd() { reset(); }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  int get() const { return fd_; }
  void reset() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }

 private:
  int fd_;
};

class SpawnActions {
 public:
  SpawnActions() {
    if (const int error = posix_spawn_file_actions_init(&actions_); error != 0)
      throw run_error("plots", "cannot prepare the child process: " + describe_errno(error));
  }
  ~SpawnActions() { posix_spawn_file_actions_destroy(&actions_); }
  SpawnActions(const SpawnActions&) = delete;
  SpawnActions& operator=(const SpawnActions&) = delete;
  posix_spawn_file_actions_t* get() { return &actions_; }

 private:
  posix_spawn_file_actions_t actions_;
};

std::string trimmed(std::string text) {
  const auto first = text.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return "";
  text = text.substr(first, text.find_last_not_of(" \t\r\n") - first + 1);
  if (text.size() > kMaxStderrChars) text = "..." + text.substr(text.size() - kMaxStderrChars);
  return text;
}

// Everything the child writes to its stderr until it closes it.
std::string read_all(const Fd& fd) {
  std::string text;
  char buffer[4096];
  for (;;) {
    const ssize_t n = ::read(fd.get(), buffer, sizeof buffer);
    if (n > 0) {
      text.append(buffer, static_cast<std::size_t>(n));
    } else if (n == 0 || errno != EINTR) {
      return text;
    }
  }
}

// The child's stdin and stdout on /dev/null, its stderr into `stderr_fd`, and nothing else of
// the caller's: a file another thread has open through HDF5 holds HDF5's flock, and a child
// holding a copy for the minutes matplotlib draws kept it locked after that thread closed it
// (as the granule reader did: core/spawned_reader.hpp).
void redirect(SpawnActions& actions, const Fd& stderr_fd) {
  int error =
      posix_spawn_file_actions_addopen(actions.get(), STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  if (error == 0)
    error =
        posix_spawn_file_actions_addopen(actions.get(), STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  if (error == 0)
    error = posix_spawn_file_actions_adddup2(actions.get(), stderr_fd.get(), STDERR_FILENO);
  if (error == 0)
    error = posix_spawn_file_actions_addclosefrom_np(actions.get(), STDERR_FILENO + 1);
  if (error != 0)
    throw run_error("plots", "cannot prepare the child process: " + describe_errno(error));
}

}  // namespace

void write_plots(const fs::path& out_dir, const std::string& script_name) {
  const fs::path script = share_dir() / "plots" / script_name;
  std::error_code ignored;
  if (!fs::is_regular_file(script, ignored)) {
    throw run_error("plots", "cannot find " + script.string() +
                                 " (set GLASWAVE_SHARE to the folder that holds plots/)");
  }
  // Debian's python3 has the matplotlib that scripts/setup installs; a python3 first on PATH
  // (a virtual environment) may not.
  const bool debian_python = fs::exists("/usr/bin/python3", ignored);
  const std::string python = debian_python ? "/usr/bin/python3" : "python3";
  // -B: no bytecode written next to the script, which may sit in a read-only install.
  std::vector<std::string> args = {python, "-B", script.string(), out_dir.string()};
  std::vector<char*> argv;
  for (std::string& arg : args) argv.push_back(arg.data());
  argv.push_back(nullptr);

  // Close-on-exec, so that no other child started meanwhile holds the write end open.
  int ends[2];
  if (::pipe2(ends, O_CLOEXEC) != 0)
    throw run_error("plots", "cannot create a pipe: " + describe_errno(errno));
  Fd read_end(ends[0]), write_end(ends[1]);

  SpawnActions actions;
  redirect(actions, write_end);
  pid_t pid = -1;
  int error = 0;
  {
    // Under the HDF5 lock: until the script runs, the child holds a copy of every descriptor
    // (see redirect); posix_spawn returns once they are closed.
    const std::lock_guard lock(netcdf_library_mutex());
    error = debian_python
                ? posix_spawn(&pid, argv[0], actions.get(), nullptr, argv.data(), environ)
                : posix_spawnp(&pid, argv[0], actions.get(), nullptr, argv.data(), environ);
  }
  if (error != 0) throw run_error("plots", "cannot start " + python + ": " + describe_errno(error));
  write_end.reset();  // so that reading ends when the child exits

  std::string errors = read_all(read_end);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR)
      throw run_error("plots", "cannot wait for " + python + ": " + describe_errno(errno));
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return;

  const std::string how = WIFEXITED(status)
                              ? "exited with status " + std::to_string(WEXITSTATUS(status))
                              : "was killed by signal " + std::to_string(WTERMSIG(status));
  // The message is one line: the script's last line (a traceback ends with the exception);
  // the whole of its output goes to plots.log beside the products.
  const std::string message = trimmed(errors);
  std::string last = message.substr(message.find_last_of('\n') + 1);
  if (last.size() > kMaxMessageChars) last = last.substr(0, kMaxMessageChars) + "...";
  std::string log_note;
  if (!message.empty() && message.find('\n') != std::string::npos) {
    const fs::path log = out_dir / "plots.log";
    std::ofstream out(log, std::ios::binary);
    out << message << '\n';
    if (out) log_note = " (its whole output in " + log.string() + ")";
  }
  throw run_error("plots", script.filename().string() + " " + how +
                               (last.empty() ? "" : ": " + last) + log_note);
}

std::string plots_after_products(const fs::path& out_dir, const std::string& script_name) {
  try {
    write_plots(out_dir, script_name);
    return "";
  } catch (const Error& error) {
    return std::string(error.what()) + " (the products are complete, the plots not drawn)";
  }
}

}  // namespace glaswave
