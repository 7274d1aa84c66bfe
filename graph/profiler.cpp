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

std::vector<ProfileEntry> profile_entries() {
  std::vector<ProfileEntry> rows;
  {
    std::lock_guard<std::mutex> lock(profile().mutex);
    for (const auto& [key, e] : profile().entries)
      rows.push_back({key.first, key.second, e.calls, e.ms});
  }
  std::sort(rows.begin(), rows.end(), [](auto& a, auto& b) { return a.ms > b.ms; });
  return rows;
}

std::string profile_report() {
  std::string out = "op                          pass   calls    total ms     ms/call\n";
  char line[160];
  for (const ProfileEntry& e : profile_entries()) {
    std::snprintf(line, sizeof line, "%-27s %-5s %7lld %11.3f %11.4f\n", e.op.c_str(),
                  e.backward ? "bwd" : "fwd", e.calls, e.ms, e.ms / static_cast<double>(e.calls));
    out += line;
  }
  return out;
}

}  // namespace weft
