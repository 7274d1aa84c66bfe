#include "capture/training/loss_log.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <set>
#include <string_view>

#include "graph/atomic_file.h"
#include "files/text_reader.h"
#include "graph/error.h"

namespace weft::capture {

namespace {

// ---------------------------------------------------------------------------------
// CSV

bool valid_name(const std::string& s) {
  return !s.empty() && s.find_first_of(",\r\n") == std::string::npos;
}

std::string format_value(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

// A value cell: a number, nan, inf or -inf (what format_value writes).
bool parse_value(std::string_view s, double& v) {
  if (s.empty()) return false;
  const char* first = s.data();
  const char* last = first + s.size();
  const auto [ptr, ec] = std::from_chars(first, last, v);
  if (ptr != last) return false;
  if (ec == std::errc::result_out_of_range) {  // denormals read as strtod reads them
    v = std::strtod(std::string(s).c_str(), nullptr);
    return true;
  }
  return ec == std::errc();
}

std::vector<std::string_view> split_commas(std::string_view line) {
  std::vector<std::string_view> cells;
  size_t start = 0;
  while (true) {
    const size_t comma = line.find(',', start);
    cells.push_back(line.substr(start, comma == std::string_view::npos ? comma : comma - start));
    if (comma == std::string_view::npos) return cells;
    start = comma + 1;
  }
}

std::string format_row(const LossRow& row, const std::vector<std::string>& columns) {
  std::string line = std::to_string(row.step) + "," + row.stage;
  for (const std::string& c : columns) {
    line += ',';
    const auto it = row.terms.find(c);
    if (it != row.terms.end()) line += format_value(it->second);
  }
  line += '\n';
  return line;
}

std::string format_csv(const std::vector<std::string>& columns, const std::vector<LossRow>& rows) {
  if (rows.empty()) return "";
  std::string text = "step,stage";
  for (const std::string& c : columns) text += "," + c;
  text += '\n';
  for (const LossRow& r : rows) text += format_row(r, columns);
  return text;
}

struct LossCsv {
  std::vector<std::string> columns;
  std::vector<LossRow> rows;
};

LossCsv parse_loss_csv(std::string text, const std::string& path) {
  TextReader in(std::move(text), path);
  LossCsv out;
  if (!in.next_nonempty_line()) return out;
  const std::vector<std::string_view> header = split_commas(in.line());
  if (header.size() < 2 || header[0] != "step" || header[1] != "stage")
    in.fail("expected the header step,stage,<terms...>, found '", in.line(), "'");
  for (size_t i = 2; i < header.size(); ++i) {
    const std::string name(header[i]);
    if (name.empty() || name == "step" || name == "stage" ||
        std::find(out.columns.begin(), out.columns.end(), name) != out.columns.end())
      in.fail("header: empty, reserved or repeated term name '", name, "'");
    out.columns.push_back(name);
  }
  const size_t ncells = 2 + out.columns.size();
  while (in.next_line()) {
    if (in.tokens().empty()) continue;  // blank line
    const std::vector<std::string_view> cells = split_commas(in.line());
    if (cells.size() != ncells)
      in.fail("expected ", ncells, " comma-separated cells (step, stage and ", out.columns.size(),
              " terms), found ", cells.size());
    LossRow row;
    long long step = 0;
    if (!parse_int(cells[0], step)) in.fail("expected an integer step, found '", cells[0], "'");
    row.step = step;
    if (!out.rows.empty() && row.step <= out.rows.back().step)
      in.fail("step ", row.step, " does not follow step ", out.rows.back().step);
    row.stage = std::string(cells[1]);
    if (row.stage.empty()) in.fail("empty stage");
    for (size_t i = 2; i < ncells; ++i) {
      if (cells[i].empty()) continue;
      double v = 0;
      if (!parse_value(cells[i], v))
        in.fail("expected a number for '", out.columns[i - 2], "', found '", cells[i], "'");
      row.terms[out.columns[i - 2]] = v;
    }
    out.rows.push_back(std::move(row));
  }
  return out;
}

}  // namespace

LossLog::LossLog(std::string path, int64_t resume_after_step) : path_(std::move(path)) {
  if (resume_after_step >= 0 && std::filesystem::exists(path_)) {
    std::string text = read_file_bytes(path_);
    // A run killed mid-write may leave an unterminated last line: it is not a row.
    if (!text.empty() && text.back() != '\n') {
      const size_t nl = text.rfind('\n');
      text.erase(nl == std::string::npos ? 0 : nl + 1);
    }
    LossCsv csv = parse_loss_csv(std::move(text), path_);
    std::set<std::string> used;
    for (LossRow& r : csv.rows) {
      if (r.step > resume_after_step) break;
      for (const auto& [name, v] : r.terms) used.insert(name);
      rows_.push_back(std::move(r));
    }
    for (const std::string& c : csv.columns)
      if (used.count(c)) columns_.push_back(c);
  }
  rewrite();
}

void LossLog::rewrite() {
  file_.reset();
  write_text_atomically(path_, format_csv(columns_, rows_));
  file_.reset(std::fopen(path_.c_str(), "ab"));
  if (!file_) fail(path_, ": cannot open for appending: ", std::strerror(errno));
}

void LossLog::append(const LossRow& row) {
  WEFT_CHECK(valid_name(row.stage), path_, ": step ", row.step,
             ": the stage must be a non-empty name without commas or line breaks, got '", row.stage, "'");
  WEFT_CHECK(rows_.empty() || row.step > rows_.back().step, path_, ": step ", row.step,
             " does not follow the last logged step ", rows_.empty() ? 0 : rows_.back().step);
  std::vector<std::string> added;
  for (const auto& [name, v] : row.terms) {
    WEFT_CHECK(valid_name(name) && name != "step" && name != "stage", path_, ": step ", row.step,
               ": bad loss term name '", name, "' (empty, reserved, or holds a comma or line break)");
    if (std::find(columns_.begin(), columns_.end(), name) == columns_.end()) added.push_back(name);
  }
  const bool whole_file = rows_.empty() || !added.empty() || !file_;
  rows_.push_back(row);
  for (auto& [name, v] : rows_.back().terms) parse_value(format_value(v), v);  // as in the file
  columns_.insert(columns_.end(), added.begin(), added.end());
  if (whole_file) {
    try {
      rewrite();
    } catch (...) {
      rows_.pop_back();
      columns_.resize(columns_.size() - added.size());
      throw;
    }
    return;
  }
  const std::string line = format_row(row, columns_);
  if (std::fwrite(line.data(), 1, line.size(), file_.get()) != line.size() ||
      std::fflush(file_.get()) != 0) {
    const int err = errno;
    rows_.pop_back();
    file_.reset();  // the next append rewrites the whole file, mending a partial line
    fail(path_, ": cannot append the loss row of step ", row.step, ": ", std::strerror(err));
  }
}

std::vector<LossRow> read_loss_log(const std::string& path) {
  return parse_loss_csv(read_file_bytes(path), path).rows;
}

}  // namespace weft::capture
