// glibc malloc tuning, applied when the library loads.
//
// Tensors of a few MB are allocated and freed on every forward and backward pass. With
// glibc's defaults such blocks are mapped fresh from the kernel (mmap, or the heap top
// trimmed and regrown), so every pass page-faults its buffers in again; on this
// machine's virtualised kernel a fault costs several µs, and a ResNet-50 stem conv at
// batch 8 (an 8 MB output) ran 5× slower than its GEMM for the first dozens of calls
// (bench_conv2d --layer stem: 16 ms median of 15, 3 ms median of 60). Keeping blocks up
// to 32 MB (glibc's maximum threshold) on the heap and trimming it only beyond 1 GiB of
// free memory at its top lets freed buffers be reused without faults. The process's
// resident size then stays at its peak instead of shrinking between passes.
// WEFT_MALLOC_DEFAULTS=1 leaves glibc's defaults alone.
#include <malloc.h>

#include <cstdlib>
#include <cstring>

namespace weft {
namespace {

struct HeapTuning {
  HeapTuning() {
    const char* keep = std::getenv("WEFT_MALLOC_DEFAULTS");
    if (keep && std::strcmp(keep, "1") == 0) return;
#if defined(__GLIBC__)
    mallopt(M_MMAP_THRESHOLD, 32 << 20);
    mallopt(M_TRIM_THRESHOLD, 1 << 30);
#endif
  }
};
const HeapTuning heap_tuning;

}  // namespace
}  // namespace weft
