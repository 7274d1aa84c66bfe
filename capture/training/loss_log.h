#pragma once
// The training run's record of losses, RUN/losses.csv (its plot, RUN/losses.png, is
// capture/plots/loss_plot.h's plot_losses).
//
// CSV: a header `step,stage,<term>...` (terms in the order first seen), one row per
// logged step, values printed with %.9g (nan, inf, -inf for non-finite values), an
// empty cell where a row has no value for a term (a later stage added it). Rows are
// appended and flushed one by one, so a killed run keeps every row it logged; resuming
// from a checkpoint drops the rows after it, which the resumed run writes again.
#include <cstdint>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "capture/plots/loss_plot.h"

namespace weft::capture {


class LossLog {
 public:
  // Opens `path` for appending. With resume_after_step >= 0 it keeps the rows with
  // step <= resume_after_step of an existing file (none if there is no file; a torn,
  // unterminated last line is dropped) and rewrites it atomically; with
  // resume_after_step < 0 it starts a new, empty file.
  LossLog(std::string path, int64_t resume_after_step);
  // Appends one row and flushes it to the file. A term not seen before widens the
  // header: the whole file is rewritten atomically, earlier rows get empty cells.
  // Errors: step not above the last one, a stage or term name that is empty or holds a
  // comma or line break, a term named "step" or "stage", a failed write.
  void append(const LossRow& row);
  // Every row of the file, values as written (%.9g), those kept on resume included.
  const std::vector<LossRow>& rows() const { return rows_; }
  // The term columns, in header order.
  const std::vector<std::string>& columns() const { return columns_; }
  const std::string& path() const { return path_; }

 private:
  void rewrite();
  struct FileCloser {
    void operator()(std::FILE* f) const { std::fclose(f); }
  };
  std::string path_;
  std::vector<std::string> columns_;
  std::vector<LossRow> rows_;
  std::unique_ptr<std::FILE, FileCloser> file_;
};

// Reads a losses.csv; an empty file has no rows. A malformed header or row (wrong
// number of cells, a step that is not an integer or not increasing, a value that is not
// a number) is a weft::Error "losses.csv:LINE: what".
std::vector<LossRow> read_loss_log(const std::string& path);

}  // namespace weft::capture
