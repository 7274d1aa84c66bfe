#pragma once
// Line-by-line reading of text formats with errors that name "file:line: what".
// Every parser of weft's text formats uses it, so that a malformed file gets one clear weft::Error
// and never a crash: numbers are parsed strictly (no NaN/inf, no trailing junk).
#include <charconv>
#include <string>
#include <string_view>
#include <vector>

#include "graph/error.h"

namespace weft {

// Reads a whole file into memory; throws weft::Error naming the file when unreadable.
std::string read_file_bytes(const std::string& path);

// The file name shown in messages (the last path component).
std::string display_name(const std::string& path);

class TextReader {
 public:
  // Reads `path` from disk.
  explicit TextReader(const std::string& path);
  // Parses `text` as if it came from `path` (for tests and in-memory data).
  TextReader(std::string text, std::string path);

  // Advances to the next line (CR/LF/CRLF line ends); false at the end of the file.
  bool next_line();
  // Advances to the next line holding at least one token; false at the end of the file.
  bool next_nonempty_line();
  std::string_view line() const { return line_; }
  int line_number() const { return line_number_; }
  // The whitespace-separated tokens of the current line.
  const std::vector<std::string_view>& tokens() const { return tokens_; }
  bool at_end() const { return pos_ >= text_.size(); }

  const std::string& path() const { return path_; }
  const std::string& name() const { return name_; }

  // Throws weft::Error "name:line: parts...".
  template <class... Parts>
  [[noreturn]] void fail(const Parts&... parts) const {
    weft::fail(name_, ":", line_number_, ": ", parts...);
  }
  // Throws "name: unexpected end of file, expected <what>".
  [[noreturn]] void fail_eof(std::string_view what) const;

  // Strict conversions of a token of the current line; `what` names the field in errors.
  double to_double(std::string_view token, std::string_view what) const;
  long long to_int(std::string_view token, std::string_view what) const;
  // Token `i` of the current line, or an error naming what was expected there.
  std::string_view token(size_t i, std::string_view what) const;
  // Requires exactly/at least `n` tokens on the current line.
  void expect_tokens(size_t n, std::string_view what) const;
  void expect_min_tokens(size_t n, std::string_view what) const;

 private:
  void split();
  std::string text_;
  std::string path_;
  std::string name_;
  size_t pos_ = 0;
  int line_number_ = 0;
  std::string_view line_;
  std::vector<std::string_view> tokens_;
};

// Strict number parsing shared by the parsers: the whole token must be a finite number.
// Returns false instead of throwing, so callers can phrase their own message.
bool parse_double(std::string_view token, double& value);
bool parse_int(std::string_view token, long long& value);

}  // namespace weft
