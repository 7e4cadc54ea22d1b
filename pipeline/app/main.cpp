// The glaswave command.
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <optional>

#include "pipeline/app/cli.hpp"
#include "pipeline/engine/cluster.hpp"

int main(int argc, char** argv) {
  // A file size limit (ulimit -f) fails the write, which says so, instead of killing the process.
  std::signal(SIGXFSZ, SIG_IGN);
  std::optional<glaswave::MpiSession> mpi(std::in_place, argc, argv);  // only under mpirun
  const int status = glaswave::run_command_line(argc, argv);
  if (status == 0) return 0;
  // After a failure, a product given up on a full disk may still be open in HDF5, whose exit
  // handler would crash flushing it: the error is reported, so end here, without them.
  mpi.reset();
  std::fflush(nullptr);
  _exit(status);
}
