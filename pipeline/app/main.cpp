// The glaswave command.
#include <csignal>

#include "pipeline/app/cli.hpp"
#include "pipeline/engine/cluster.hpp"

int main(int argc, char** argv) {
  // A file size limit (ulimit -f) fails the write, which says so, instead of killing the process.
  std::signal(SIGXFSZ, SIG_IGN);
  const glaswave::MpiSession mpi(argc, argv);  // only under mpirun
  return glaswave::run_command_line(argc, argv);
}
