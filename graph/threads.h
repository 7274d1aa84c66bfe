#pragma once
// One thread budget for the whole process: OpenMP inside numeric kernels (Eigen GEMM,
// conv, elementwise) and TBB for task-level work (simulation windows, data loading).
// Set once, from WEFT_NUM_THREADS or the command line; default: all cores.
namespace weft {

void set_num_threads(int n);  // n <= 0: all hardware threads
int num_threads();

}  // namespace weft
