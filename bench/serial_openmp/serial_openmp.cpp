// A measurement tool, not part of weft: preloaded (LD_PRELOAD=build/bench/libserial_openmp.so)
// it runs every OpenMP parallel region on the calling thread without libgomp's team set-up
// and tear-down. Debian's CHOLMOD opens several parallel regions per supernode; even on
// one thread each costs a team allocation and a futex wake-up. Comparing a single-threaded
// benchmark with and without this library prices that overhead, i.e. what a CHOLMOD built
// without OpenMP would save (docs/BENCHMARKS.md, Simulator). Only valid for runs on one
// thread: with it, every region of the process is serial.
extern "C" void GOMP_parallel(void (*body)(void*), void* data, unsigned /*num_threads*/, unsigned /*flags*/) {
  body(data);
}
