#pragma once
// Per-op timing of forward and backward passes. Off by default (one branch per op
// call); on when WEFT_PROFILE=1 is set or set_profiling(true) is called. The report
// lists ops by total time, so a slow kernel shows at the top.
#include <string>

namespace weft {

bool profiling_enabled();
void set_profiling(bool on);
void reset_profile();
// Records one call of `op` in the forward ("fwd") or backward ("bwd") pass.
void record_op_time(const std::string& op, bool backward, double milliseconds);
// A table: op, pass, calls, total ms, ms per call; sorted by total time.
std::string profile_report();

}  // namespace weft
