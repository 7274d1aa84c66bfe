#include "nn/process_group.h"

#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <thread>

#include "graph/error.h"

#ifdef WEFT_WITH_MPI
#include <mpi.h>
#endif

namespace weft::nn {

namespace {

// The launcher's variables: OpenMPI's mpirun, PMI (MPICH's hydra, Slurm's srun --mpi=pmi2)
// and PMIx (srun --mpi=pmix, OpenMPI 4+).
bool launched_by_mpi() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"})
    if (std::getenv(v)) return true;
  return false;
}

[[maybe_unused]] int launcher_size() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"})
    if (const char* s = std::getenv(v)) return std::atoi(s);
  return 1;
}

[[maybe_unused]] int launcher_rank() {
  for (const char* v : {"OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK"})
    if (const char* s = std::getenv(v)) return std::atoi(s);
  return 0;
}

// Ends the process when a collective waits past its deadline: a thread that sleeps until
// armed, then until the deadline or disarm(). It writes with fprintf and leaves with
// _exit: the main thread is blocked inside MPI, so nothing else can run safely.
class Watchdog {
 public:
  ~Watchdog() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    cv_.notify_all();
    if (thread_.joinable()) thread_.join();
  }
  void arm(const std::string& who, const char* what, double seconds) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!thread_.joinable()) thread_ = std::thread([this] { loop(); });
    armed_ = true;
    ++generation_;
    who_ = who;
    what_ = what;
    seconds_ = seconds;
    deadline_ = std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                                       std::chrono::duration<double>(seconds));
    cv_.notify_all();
  }
  void disarm() {
    std::lock_guard<std::mutex> lock(mutex_);
    armed_ = false;
    cv_.notify_all();
  }

 private:
  void loop() {
    std::unique_lock<std::mutex> lock(mutex_);
    while (!stop_) {
      if (!armed_) {
        cv_.wait(lock);
        continue;
      }
      const uint64_t generation = generation_;
      if (cv_.wait_until(lock, deadline_, [&] { return stop_ || !armed_ || generation_ != generation; })) continue;
      std::fprintf(stderr,
                   "weft: %s waited %.0f s in the collective '%s' for the other ranks: one of them hangs or has "
                   "died; ending the job (WEFT_MPI_TIMEOUT_S sets the wait)\n",
                   who_.c_str(), seconds_, what_.c_str());
      std::fflush(stderr);
      ::_exit(3);
    }
  }
  std::thread thread_;
  std::mutex mutex_;
  std::condition_variable cv_;
  bool armed_ = false, stop_ = false;
  uint64_t generation_ = 0;
  std::string who_, what_;
  double seconds_ = 0;
  std::chrono::steady_clock::time_point deadline_;
};

Watchdog& watchdog() {
  static Watchdog w;
  return w;
}

// Arms the watchdog for one collective.
class Deadline {
 public:
  Deadline(const ProcessGroup& g, const char* what) { watchdog().arm(g.describe(), what, g.timeout_seconds()); }
  ~Deadline() { watchdog().disarm(); }
};

#ifdef WEFT_WITH_MPI
void check(int code, const ProcessGroup& g, const char* what) {
  if (code == MPI_SUCCESS) return;
  char text[MPI_MAX_ERROR_STRING];
  int length = 0;
  MPI_Error_string(code, text, &length);
  fail(g.describe(), ": MPI failed in the collective '", what, "': ", std::string(text, length));
}

// One blocking in-place all-reduce of `n` values, under the group's deadline.
void all_reduce(const ProcessGroup& g, void* values, size_t n, MPI_Datatype type, MPI_Op op,
                const char* what) {
  Deadline deadline(g, what);
  check(MPI_Allreduce(MPI_IN_PLACE, values, int(n), type, op, MPI_COMM_WORLD), g, what);
}
#endif

}  // namespace

bool ProcessGroup::built_with_mpi() {
#ifdef WEFT_WITH_MPI
  return true;
#else
  return false;
#endif
}

ProcessGroup& ProcessGroup::world() {
  static ProcessGroup group;
  return group;
}

ProcessGroup::ProcessGroup() {
  char name[256] = {0};
  ::gethostname(name, sizeof(name) - 1);
  host_ = name;
  if (const char* t = std::getenv("WEFT_MPI_TIMEOUT_S")) {
    const double s = std::atof(t);
    WEFT_CHECK(s > 0, "WEFT_MPI_TIMEOUT_S: expected a positive number of seconds, found '", t, "'");
    timeout_s_ = s;
  }
  if (!launched_by_mpi()) return;
#ifdef WEFT_WITH_MPI
  int provided = 0;
  MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
  mpi_ = true;
  // Errors come back as codes (turned into weft::Errors naming the collective) instead
  // of MPI's default of ending the job without a word from weft.
  MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
#else
  if (launcher_size() > 1)
    fail("weft was built without MPI (CMake option WEFT_WITH_MPI off, or no MPI found at configure time) "
         "but was started as rank ", launcher_rank(), " of ", launcher_size(),
         " by an MPI launcher; each rank would train alone. Rebuild with MPI (scripts/setup.sh installs it) or run "
         "one process");
#endif
}

std::string ProcessGroup::describe() const {
  return "rank " + std::to_string(rank_) + " of " + std::to_string(size_) + " on " + host_;
}

void ProcessGroup::all_reduce_sum(std::span<float> values, const char* what, int64_t bucket_elements) {
  if (!distributed() || values.empty()) return;
#ifdef WEFT_WITH_MPI
  WEFT_CHECK(bucket_elements > 0 && bucket_elements <= (int64_t(1) << 30), "all_reduce_sum: bucket of ",
             bucket_elements, " elements");
  Deadline deadline(*this, what);
  std::vector<MPI_Request> requests;
  for (size_t first = 0; first < values.size(); first += size_t(bucket_elements)) {
    const int n = int(std::min<size_t>(size_t(bucket_elements), values.size() - first));
    requests.emplace_back();
    check(MPI_Iallreduce(MPI_IN_PLACE, values.data() + first, n, MPI_FLOAT, MPI_SUM, MPI_COMM_WORLD,
                         &requests.back()),
          *this, what);
  }
  check(MPI_Waitall(int(requests.size()), requests.data(), MPI_STATUSES_IGNORE), *this, what);
#endif
}

void ProcessGroup::all_reduce_sum(std::span<double> values, const char* what) {
  if (!distributed() || values.empty()) return;
#ifdef WEFT_WITH_MPI
  all_reduce(*this, values.data(), values.size(), MPI_DOUBLE, MPI_SUM, what);
#endif
}

void ProcessGroup::all_reduce_min(std::span<uint64_t> values, const char* what) {
  if (!distributed() || values.empty()) return;
#ifdef WEFT_WITH_MPI
  all_reduce(*this, values.data(), values.size(), MPI_UINT64_T, MPI_MIN, what);
#endif
}

void ProcessGroup::all_reduce_max(std::span<uint64_t> values, const char* what) {
  if (!distributed() || values.empty()) return;
#ifdef WEFT_WITH_MPI
  all_reduce(*this, values.data(), values.size(), MPI_UINT64_T, MPI_MAX, what);
#endif
}

void ProcessGroup::broadcast(std::span<int64_t> values, int root, const char* what) {
  if (!distributed() || values.empty()) return;
#ifdef WEFT_WITH_MPI
  Deadline deadline(*this, what);
  check(MPI_Bcast(values.data(), int(values.size()), MPI_INT64_T, root, MPI_COMM_WORLD), *this, what);
#endif
}

void ProcessGroup::barrier(const char* what) {
  if (!distributed()) return;
#ifdef WEFT_WITH_MPI
  Deadline deadline(*this, what);
  check(MPI_Barrier(MPI_COMM_WORLD), *this, what);
#endif
}

void ProcessGroup::abort(const std::string& message, int code) {
  if (!message.empty()) std::fprintf(stderr, "weft: %s: %s\n", describe().c_str(), message.c_str());
  std::fflush(stderr);
#ifdef WEFT_WITH_MPI
  if (mpi_ && !finalized_) MPI_Abort(MPI_COMM_WORLD, code);
#endif
  std::_Exit(code);
}

void ProcessGroup::finalize() {
#ifdef WEFT_WITH_MPI
  if (mpi_ && !finalized_) {
    finalized_ = true;
    MPI_Finalize();
  }
#endif
}

}  // namespace weft::nn
