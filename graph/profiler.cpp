#include "graph/profiler.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <mutex>
#include <vector>

namespace weft {
namespace {

struct Entry {
  long long calls = 0;
  double ms = 0;
};

struct Profile {
  std::mutex mutex;
  std::map<std::pair<std::string, bool>, Entry> entries;
  bool enabled = [] {
    const char* env = std::getenv("WEFT_PROFILE");
    return env && env[0] == '1';
  }();
};

Profile& profile() {
  static Profile p;
  return p;
}

}  // namespace

bool profiling_enabled() { return profile().enabled; }
void set_profiling(bool on) { profile().enabled = on; }

void reset_profile() {
  std::lock_guard<std::mutex> lock(profile().mutex);
  profile().entries.clear();
}

void record_op_time(const std::string& op, bool backward, double milliseconds) {
  std::lock_guard<std::mutex> lock(profile().mutex);
  Entry& e = profile().entries[{op, backward}];
  ++e.calls;
  e.ms += milliseconds;
}

std::string profile_report() {
  std::vector<std::pair<std::pair<std::string, bool>, Entry>> rows;
  {
    std::lock_guard<std::mutex> lock(profile().mutex);
    rows.assign(profile().entries.begin(), profile().entries.end());
  }
  std::sort(rows.begin(), rows.end(), [](auto& a, auto& b) { return a.second.ms > b.second.ms; });
  std::string out = "op                          pass   calls    total ms     ms/call\n";
  char line[160];
  for (auto& [key, e] : rows) {
    std::snprintf(line, sizeof line, "%-27s %-5s %7lld %11.3f %11.4f\n", key.first.c_str(),
                  key.second ? "bwd" : "fwd", e.calls, e.ms, e.ms / static_cast<double>(e.calls));
    out += line;
  }
  return out;
}

}  // namespace weft
