// The processes of a run: one, or the K that `mpirun -np K` starts. Rank 0 alone writes; the
// others simulate their share of each batch and send the records to it. Every process calls
// the same collectives in the same order; a failure on any is agreed on, so that every process
// ends with the same error and rank 0 alone reports it. Without mpirun (or in Python) MPI is
// never initialised and this is one process that calls nothing of MPI.
#pragma once

#include <cstdint>
#include <exception>
#include <string>
#include <vector>

namespace glaswave {

class Cluster {
 public:
  // The processes of this run: MPI_COMM_WORLD when MPI is initialised, else this one.
  static Cluster& world();
  // This process alone, whatever started it: what a batch loop runs on when its work is not
  // shared (a sweep's cases).
  static Cluster& alone();

  int rank() const { return rank_; }
  int size() const { return size_; }
  // Processes on this machine (each takes its share of the cores).
  int local_size() const { return local_size_; }
  // Whether mpirun started this process (MPI runs it, even as the only process).
  bool launched() const { return launched_; }

  // Every process calls it with its failure (null when none): when any failed, every process
  // throws the failure of the lowest rank that failed, as an Error of the same kind and text
  // (in one process: the failure itself, whatever it is).
  void agree(const std::exception_ptr& failure);
  // Whether the last error came out of agree() (every process has it) rather than from this
  // process alone.
  bool failed_together() const { return failed_together_; }

  // Rank 0 receives every rank's bytes, in rank order; the others receive nothing.
  std::vector<std::string> gather(const std::string& bytes) const;
  // Rank 0's value, on every rank.
  std::int64_t broadcast(std::int64_t value) const;
  // Ends every process now with `status` (an error this process alone met).
  [[noreturn]] void abort(int status) const;

 private:
  explicit Cluster(bool world);
  int rank_ = 0, size_ = 1, local_size_ = 1;
  bool launched_ = false;
  bool failed_together_ = false;
};

// MPI for the life of the command, when mpirun started it (its environment says so); nothing
// otherwise, so that the command alone behaves as it always has.
class MpiSession {
 public:
  MpiSession(int& argc, char**& argv);
  ~MpiSession();
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;

 private:
  bool initialised_ = false;
};

}  // namespace glaswave
