#pragma once
// A progress bar for long subcommands: on a terminal, one line redrawn in place on stderr
// ("  label [#####.....] 12/40  3.1 s, ~7.2 s left"); otherwise (logs, CI) a log line at
// about every tenth of the work, so redirected output stays readable.
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <string>

namespace weft::apps {

class ProgressBar {
 public:
  explicit ProgressBar(std::string label) : label_(std::move(label)), tty_(::isatty(STDERR_FILENO)) {}

  // Reports `done` of `total` units; call with done == total once at the end.
  void update(int done, int total) {
    if (total <= 0) return;
    const auto now = std::chrono::steady_clock::now();
    if (done == 1 || start_ == std::chrono::steady_clock::time_point{}) start_ = now, first_ = done;
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    const double rate = done > first_ && elapsed > 0 ? (done - first_) / elapsed : 0;
    const double left = rate > 0 ? (total - done) / rate : 0;
    if (tty_) {
      if (done < total && std::chrono::duration<double>(now - last_).count() < 0.1) return;
      last_ = now;
      const int width = 30, filled = static_cast<int>(static_cast<long long>(width) * done / total);
      std::fprintf(stderr, "\r  %-10s [%s%s] %d/%d  %.1f s%s", label_.c_str(), std::string(filled, '#').c_str(),
                   std::string(width - filled, '.').c_str(), done, total, elapsed,
                   done < total && rate > 0 ? (", ~" + std::to_string(static_cast<int>(left + 0.5)) + " s left").c_str()
                                            : "          ");
      if (done == total) std::fprintf(stderr, "\n");
    } else {
      const int step = std::max(1, total / 10);
      if (done == total || done % step == 0) spdlog::info("{}: {}/{} ({:.1f} s)", label_, done, total, elapsed);
    }
  }

 private:
  std::string label_;
  bool tty_;
  int first_ = 0;
  std::chrono::steady_clock::time_point start_{}, last_{};
};

}  // namespace weft::apps
