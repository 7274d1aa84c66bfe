#pragma once
// Per-op timing of forward and backward passes. Off by default (one branch per op
// call); on when WEFT_PROFILE=1 is set or set_profiling(true) is called. The report
// lists ops by total time, so a slow kernel shows at the top.
#include <string>
#include <vector>

namespace weft {

bool profiling_enabled();
void set_profiling(bool on);
void reset_profile();
// Records one call of `op` in the forward ("fwd") or backward ("bwd") pass.
void record_op_time(const std::string& op, bool backward, double milliseconds);
// A table: op, pass, calls, total ms, ms per call; sorted by total time.
std::string profile_report();

// The recorded totals, sorted by total time. Besides the ops, the backward pass records
// "(gradient accumulation)": summing the gradients of a tensor used more than once and
// adding into the leaves' .grad, which the autograd engine does between ops.
struct ProfileEntry {
  std::string op;
  bool backward = false;
  long long calls = 0;
  double ms = 0;
};
std::vector<ProfileEntry> profile_entries();

}  // namespace weft
