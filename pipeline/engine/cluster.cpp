// MPI behind Cluster: the C API, called only from the main thread (MPI_THREAD_FUNNELED; the
// shots' threads never call it).
#include "pipeline/engine/cluster.hpp"

// The C API only: Open MPI's (deprecated) C++ bindings would need their own library.
#define OMPI_SKIP_MPICXX 1
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>

#include <cstdlib>
#include <cstring>

#include "core/error.hpp"

namespace glaswave {
namespace {

bool mpi_running() {
  int initialised = 0, finalised = 0;
  MPI_Initialized(&initialised);
  MPI_Finalized(&finalised);
  return initialised && !finalised;
}

// The failure as (exit status, place, message), whatever was thrown.
struct Failure {
  int kind = static_cast<int>(ErrorKind::run);
  std::string place, message;
};

Failure describe(const std::exception_ptr& failure) {
  try {
    std::rethrow_exception(failure);
  } catch (const Error& e) {
    return {e.exit_status(), e.place(), e.message()};
  } catch (const std::exception& e) {
    return {static_cast<int>(ErrorKind::run), "", e.what()};
  } catch (...) {
    return {static_cast<int>(ErrorKind::run), "", "interrupted"};
  }
}

void broadcast_text(std::string& text, int root) {
  long long size = static_cast<long long>(text.size());
  MPI_Bcast(&size, 1, MPI_LONG_LONG, root, MPI_COMM_WORLD);
  text.resize(static_cast<std::size_t>(size));
  if (size > 0) MPI_Bcast(text.data(), static_cast<int>(size), MPI_CHAR, root, MPI_COMM_WORLD);
}

}  // namespace

Cluster::Cluster(bool world) {
  if (!world || !mpi_running()) return;
  launched_ = true;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
  MPI_Comm local;
  MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &local);
  MPI_Comm_size(local, &local_size_);
  MPI_Comm_free(&local);
}

Cluster& Cluster::world() {
  static Cluster cluster(true);
  return cluster;
}

Cluster& Cluster::alone() {
  static Cluster cluster(false);
  return cluster;
}

void Cluster::agree(const std::exception_ptr& failure) {
  if (size_ == 1) {
    if (failure) std::rethrow_exception(failure);
    return;
  }
  const int mine = failure ? 1 : 0;
  std::vector<int> failed(static_cast<std::size_t>(size_));
  MPI_Allgather(&mine, 1, MPI_INT, failed.data(), 1, MPI_INT, MPI_COMM_WORLD);
  int root = -1;
  for (int r = 0; r < size_ && root < 0; ++r)
    if (failed[static_cast<std::size_t>(r)]) root = r;
  if (root < 0) return;
  Failure first;
  if (rank_ == root) first = describe(failure);
  MPI_Bcast(&first.kind, 1, MPI_INT, root, MPI_COMM_WORLD);
  broadcast_text(first.place, root);
  broadcast_text(first.message, root);
  failed_together_ = true;
  throw Error(static_cast<ErrorKind>(first.kind), first.place, first.message);
}

std::vector<std::string> Cluster::gather(const std::string& bytes) const {
  if (size_ == 1) return {bytes};
  const int size = static_cast<int>(bytes.size());
  std::vector<int> sizes(static_cast<std::size_t>(size_)), offsets(sizes.size());
  MPI_Gather(&size, 1, MPI_INT, sizes.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
  std::string all;
  if (rank_ == 0) {
    long long total = 0;
    for (std::size_t r = 0; r < sizes.size(); ++r) {
      offsets[r] = static_cast<int>(total);
      total += sizes[r];
    }
    all.resize(static_cast<std::size_t>(total));
  }
  MPI_Gatherv(bytes.data(), size, MPI_CHAR, all.data(), sizes.data(), offsets.data(), MPI_CHAR, 0,
              MPI_COMM_WORLD);
  std::vector<std::string> parts;
  if (rank_ == 0)
    for (std::size_t r = 0; r < sizes.size(); ++r)
      parts.push_back(
          all.substr(static_cast<std::size_t>(offsets[r]), static_cast<std::size_t>(sizes[r])));
  return parts;
}

std::int64_t Cluster::broadcast(std::int64_t value) const {
  if (size_ == 1) return value;
  long long v = value;
  MPI_Bcast(&v, 1, MPI_LONG_LONG, 0, MPI_COMM_WORLD);
  return v;
}

void Cluster::abort(int status) const {
  if (size_ > 1) MPI_Abort(MPI_COMM_WORLD, status);
  std::exit(status);
}

MpiSession::MpiSession(int& argc, char**& argv) {
  // mpirun (Open MPI's, or a PMI launcher's) says so in the environment; alone, no MPI at all.
  const bool launched = std::getenv("OMPI_COMM_WORLD_SIZE") != nullptr ||
                        std::getenv("PMIX_RANK") != nullptr || std::getenv("PMI_SIZE") != nullptr;
  if (!launched || mpi_running()) return;
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  initialised_ = true;
}

MpiSession::~MpiSession() {
  if (initialised_ && mpi_running()) MPI_Finalize();
}

}  // namespace glaswave
