#pragma once
// Clocks of the benchmarks: process CPU time (all threads; on a shared, loaded machine it
// is steadier than wall time) and wall time, both in milliseconds.
#include <chrono>
#include <ctime>

namespace weft::bench {

inline double cpu_ms() {
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return 1e3 * t.tv_sec + 1e-6 * t.tv_nsec;
}

inline double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace weft::bench
