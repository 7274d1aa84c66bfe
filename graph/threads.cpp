#include "graph/threads.h"

#include <omp.h>
#include <tbb/global_control.h>

#include <Eigen/Core>
#include <cstdlib>
#include <memory>
#include <thread>

namespace weft {

namespace {
int g_threads = 0;
std::unique_ptr<tbb::global_control> g_tbb_limit;

int initial_threads() {
  if (const char* env = std::getenv("WEFT_NUM_THREADS")) {
    const int n = std::atoi(env);
    if (n > 0) return n;
  }
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}
}  // namespace

void set_num_threads(int n) {
  g_threads = n > 0 ? n : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  omp_set_num_threads(g_threads);
  Eigen::setNbThreads(g_threads);
  g_tbb_limit = std::make_unique<tbb::global_control>(
      tbb::global_control::max_allowed_parallelism, static_cast<size_t>(g_threads));
}

int num_threads() {
  if (g_threads == 0) set_num_threads(initial_threads());
  return g_threads;
}

namespace {
// Apply WEFT_NUM_THREADS as soon as the library loads, before any parallel kernel runs.
const int g_initial_threads = num_threads();
}  // namespace

}  // namespace weft
