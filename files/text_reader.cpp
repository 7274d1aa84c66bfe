#include "files/text_reader.h"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace weft {

std::string read_file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, ": cannot open file for reading");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) fail(path, ": read error");
  return buffer.str();
}

std::string display_name(const std::string& path) {
  const std::string name = std::filesystem::path(path).filename().string();
  return name.empty() ? path : name;
}

TextReader::TextReader(const std::string& path)
    : TextReader(read_file_bytes(path), path) {}

TextReader::TextReader(std::string text, std::string path)
    : text_(std::move(text)), path_(std::move(path)), name_(display_name(path_)) {}

bool TextReader::next_line() {
  if (pos_ >= text_.size()) {
    line_ = {};
    tokens_.clear();
    return false;
  }
  const size_t end = text_.find_first_of("\r\n", pos_);
  const size_t stop = end == std::string::npos ? text_.size() : end;
  line_ = std::string_view(text_).substr(pos_, stop - pos_);
  pos_ = stop;
  if (pos_ < text_.size() && text_[pos_] == '\r') ++pos_;
  if (pos_ < text_.size() && text_[pos_] == '\n') ++pos_;
  ++line_number_;
  split();
  return true;
}

bool TextReader::next_nonempty_line() {
  while (next_line()) {
    if (!tokens_.empty()) return true;
  }
  return false;
}

void TextReader::split() {
  tokens_.clear();
  size_t i = 0;
  const size_t n = line_.size();
  while (i < n) {
    while (i < n && std::isspace(static_cast<unsigned char>(line_[i]))) ++i;
    if (i >= n) break;
    size_t j = i;
    while (j < n && !std::isspace(static_cast<unsigned char>(line_[j]))) ++j;
    tokens_.push_back(line_.substr(i, j - i));
    i = j;
  }
}

void TextReader::fail_eof(std::string_view what) const {
  weft::fail(name_, ":", line_number_, ": unexpected end of file, expected ", what);
}

bool parse_double(std::string_view token, double& value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const char* first = token.data();
  const char* last = first + token.size();
  const auto [ptr, ec] = std::from_chars(first, last, value);
  if (ec == std::errc::result_out_of_range && ptr == last) {
    // Underflow (e.g. ddc.skin's "2.55001e-0710", an exponent run into a vertex index)
    // reads as the nearest representable value, as strtod does; overflow stays an error.
    const std::string copy(first, last);
    value = std::strtod(copy.c_str(), nullptr);
    return std::isfinite(value);
  }
  return ec == std::errc() && ptr == last && std::isfinite(value);
}

bool parse_int(std::string_view token, long long& value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const char* first = token.data();
  const char* last = first + token.size();
  const auto [ptr, ec] = std::from_chars(first, last, value);
  return ec == std::errc() && ptr == last;
}

double TextReader::to_double(std::string_view token, std::string_view what) const {
  double value = 0;
  if (!parse_double(token, value)) fail("expected a finite number for ", what, ", found '", token, "'");
  return value;
}

long long TextReader::to_int(std::string_view token, std::string_view what) const {
  long long value = 0;
  if (!parse_int(token, value)) fail("expected an integer for ", what, ", found '", token, "'");
  return value;
}

std::string_view TextReader::token(size_t i, std::string_view what) const {
  if (i >= tokens_.size()) fail("missing ", what, " (field ", i + 1, ")");
  return tokens_[i];
}

void TextReader::expect_tokens(size_t n, std::string_view what) const {
  if (tokens_.size() != n)
    fail("expected ", n, " fields (", what, "), found ", tokens_.size());
}

void TextReader::expect_min_tokens(size_t n, std::string_view what) const {
  if (tokens_.size() < n)
    fail("expected at least ", n, " fields (", what, "), found ", tokens_.size());
}

}  // namespace weft
