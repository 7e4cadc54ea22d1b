// Runs of the built glaswave that the end-to-end tests interrupt or spread: started in the
// background and killed with SIGKILL once its journal holds some batches, or under mpirun.
#pragma once

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <thread>

#include "tests/pipeline/engine/engine_test_support.hpp"

namespace glaswave::test_support {

// Starts `glaswave ARGUMENTS` in the background, its output discarded.
inline pid_t start_glaswave(const std::string& arguments) {
  const std::string command =
      "exec " + std::string(GLASWAVE_BINARY) + " " + arguments + " >/dev/null 2>&1";
  const pid_t pid = fork();
  if (pid == 0) {
    execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  return pid;
}

inline std::uintmax_t size_or_zero(const std::filesystem::path& file) {
  std::error_code error;
  const std::uintmax_t size = std::filesystem::file_size(file, error);
  return error ? 0 : size;
}

// Kills the run with SIGKILL once its journal holds `journal_bytes` (0: at once). False when
// the run ended first.
inline bool kill_when(pid_t pid, const std::filesystem::path& journal,
                      std::uintmax_t journal_bytes) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (journal_bytes > 0 && size_or_zero(journal) < journal_bytes &&
         std::chrono::steady_clock::now() < deadline) {
    int status = 0;
    if (waitpid(pid, &status, WNOHANG) == pid) return false;
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  kill(pid, SIGKILL);
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFSIGNALED(status);
}

// Two processes on this machine whatever its cores; shared memory between them only; root
// (a container) allowed; mpirun's own notices off (-q); `options` more of mpirun's. Sanitized,
// OpenMPI's own allocations kept to the exit are not reported (openmpi_lsan.supp says why and
// how); nothing changes otherwise.
inline CommandOutcome run_mpi(int processes, const std::string& arguments,
                              const std::string& options = "") {
  const std::string root = geteuid() == 0 ? " --allow-run-as-root" : "";
  const std::string lsan = std::string("LSAN_OPTIONS=\"${LSAN_OPTIONS:+$LSAN_OPTIONS:}") +
                           "suppressions=" + GLASWAVE_SOURCE_DIR +
                           "/tests/pipeline/app/openmpi_lsan.supp:fast_unwind_on_malloc=0:"
                           "print_suppressions=0\" ";
  return run_command(lsan + "mpirun -q --oversubscribe --mca btl self,vader" + root + " " +
                     options + " -np " + std::to_string(processes) + " " + GLASWAVE_BINARY + " " +
                     arguments + " 2>&1");
}

}  // namespace glaswave::test_support
