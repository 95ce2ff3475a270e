#pragma once
// Shared by the plain-text mesh readers and writers (OBJ, TetGen .node/.ele): whole-file reads,
// whitespace tokens per line with '#' comments removed, numbers parsed with std::from_chars (locale
// independent, exact) and errors that name FILE:LINE so a person can open the file at the spot.
#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "engine/core/error.hpp"

namespace phaco::text {

inline std::string read_file(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string() + ": cannot open file for reading");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

inline void write_file(const std::filesystem::path& file, const std::string& text) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  if (!out) throw InputError(file.string() + ": cannot open file for writing");
  out.write(text.data(), static_cast<std::streamsize>(text.size()));
  out.close();
  if (!out) throw InputError(file.string() + ": write failed (disk full or no permission?)");
}

// Shortest text that reads back to the same double (round trip is exact).
inline void append_number(std::string& out, double value) {
  char buf[32];
  const auto res = std::to_chars(buf, buf + sizeof buf, value);
  out.append(buf, res.ptr);
}

inline void append_number(std::string& out, uint64_t value) {
  char buf[24];
  const auto res = std::to_chars(buf, buf + sizeof buf, value);
  out.append(buf, res.ptr);
}

// Iterates the lines of a text, splitting each into tokens; comments after '#' are dropped.
class LineTokens {
 public:
  LineTokens(std::filesystem::path file, std::string text)
      : file_(std::move(file)), text_(std::move(text)) {}

  // Advances to the next line; false at the end of the text. Blank lines yield empty tokens().
  bool next() {
    if (pos_ >= text_.size()) return false;
    size_t end = text_.find('\n', pos_);
    if (end == std::string::npos) end = text_.size();
    std::string_view line(text_.data() + pos_, end - pos_);
    pos_ = end + 1;
    ++line_no_;
    if (const size_t hash = line.find('#'); hash != std::string_view::npos)
      line = line.substr(0, hash);
    tokens_.clear();
    size_t i = 0;
    while (i < line.size()) {
      while (i < line.size() && is_space(line[i])) ++i;
      size_t j = i;
      while (j < line.size() && !is_space(line[j])) ++j;
      if (j > i) tokens_.push_back(line.substr(i, j - i));
      i = j;
    }
    return true;
  }

  // Advances to the next line that has tokens; false at the end of the text.
  bool next_nonempty() {
    while (next()) {
      if (!tokens_.empty()) return true;
    }
    return false;
  }

  const std::vector<std::string_view>& tokens() const { return tokens_; }
  size_t line() const { return line_no_; }

  [[noreturn]] void fail(const std::string& message) const {
    throw InputError(file_.string() + ":" + std::to_string(line_no_) + ": " + message);
  }

  double finite(std::string_view token, const char* what) const {
    double value = 0.0;
    const auto res = std::from_chars(token.data(), token.data() + token.size(), value);
    if (res.ec != std::errc() || res.ptr != token.data() + token.size()) {
      fail(std::string("bad number '") + std::string(token) + "' for " + what);
    }
    if (!std::isfinite(value))
      fail(std::string("non-finite ") + what + " '" + std::string(token) + "'");
    return value;
  }

  int64_t integer(std::string_view token, const char* what) const {
    int64_t value = 0;
    const auto res = std::from_chars(token.data(), token.data() + token.size(), value);
    if (res.ec != std::errc() || res.ptr != token.data() + token.size()) {
      fail(std::string("bad integer '") + std::string(token) + "' for " + what);
    }
    return value;
  }

 private:
  static bool is_space(char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
  }

  std::filesystem::path file_;
  std::string text_;
  size_t pos_ = 0;
  size_t line_no_ = 0;
  std::vector<std::string_view> tokens_;
};

}  // namespace phaco::text
