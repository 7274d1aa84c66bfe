#pragma once
// The processes of a data-parallel job and the few collectives training needs. Over MPI
// when weft was built with it (CMake option WEFT_WITH_MPI) and the process was started by
// an MPI launcher (mpirun, mpiexec, srun: found by the variables they set); otherwise one
// process on its own, where every collective is the identity. nn/process_group.cpp is the
// only file of weft that includes mpi.h: MPI stays out of the graph, the ops and the
// trainer's numerics.
//
// Failures end the job within a bounded time rather than hang it:
// - a rank that dies (a signal, an exit without MPI_Finalize) is seen by the launcher,
//   which ends the others and names the rank (OpenMPI: "mpirun noticed that process
//   rank 1 ... exited on signal 9");
// - an error on one rank goes through abort(), which logs it with the rank and ends the
//   job (MPI_Abort);
// - a rank that waits in a collective for longer than the timeout (a peer that hangs, or
//   a launcher that failed to notice a death) prints which collective of which rank
//   waited and exits, which the launcher turns into the end of the job. The timeout is
//   WEFT_MPI_TIMEOUT_S seconds (default 1800: rank 0 validates and writes checkpoints
//   while the others wait in the next step's collective).
// All calls come from one thread (MPI_THREAD_FUNNELED): the thread that called world().
#include <cstdint>
#include <span>
#include <string>

namespace weft::nn {

class ProcessGroup {
 public:
  // The job's processes (MPI_COMM_WORLD), initialising MPI on the first call when the
  // process was started by an MPI launcher. A process started as one of several ranks by
  // a launcher while weft was built without MPI is a weft::Error (each rank would train
  // alone and overwrite the others' files).
  static ProcessGroup& world();
  static bool built_with_mpi();

  int rank() const { return rank_; }
  int size() const { return size_; }
  bool distributed() const { return size_ > 1; }
  bool is_root() const { return rank_ == 0; }
  const std::string& host() const { return host_; }
  // "rank R of N on HOST", for messages.
  std::string describe() const;

  // In place, on every rank; `what` names the collective in timeout and error messages.
  // Large arrays go out in buckets of at most bucket_elements, all in flight at once.
  void all_reduce_sum(std::span<float> values, const char* what, int64_t bucket_elements = 1 << 22);
  void all_reduce_sum(std::span<double> values, const char* what);
  void all_reduce_min(std::span<uint64_t> values, const char* what);
  void all_reduce_max(std::span<uint64_t> values, const char* what);
  void broadcast(std::span<int64_t> values, int root, const char* what);
  void barrier(const char* what);

  // Writes `message` (unless empty: the caller logged it) with this rank's name to stderr
  // and ends every rank of the job (exit code `code`). One rank alone: exits.
  [[noreturn]] void abort(const std::string& message, int code = 1);
  // Ends MPI cleanly (every rank calls it once, at the end); no-op without MPI.
  void finalize();

  double timeout_seconds() const { return timeout_s_; }

 private:
  ProcessGroup();
  int rank_ = 0, size_ = 1;
  bool mpi_ = false, finalized_ = false;
  double timeout_s_ = 1800;
  std::string host_;
};

}  // namespace weft::nn
