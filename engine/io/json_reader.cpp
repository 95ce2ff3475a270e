#include "engine/io/json_reader.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <vector>

#include "engine/core/error.hpp"

namespace phaco::io {

using nlohmann::json;

namespace {

constexpr std::size_t kMaxQuoted = 60;  // user text echoed in messages is cut to this length

std::string single_quoted(std::string_view text) {
  std::string out = "'";
  out += text.substr(0, kMaxQuoted);
  if (text.size() > kMaxQuoted) out += "...";
  out += "'";
  return out;
}

// Line and column (both from 1) of the character at byte `offset` of `text`.
std::pair<std::size_t, std::size_t> line_column(std::string_view text, std::size_t offset) {
  offset = std::min(offset, text.size());
  const std::string_view before = text.substr(0, offset);
  const std::size_t line =
      1 + static_cast<std::size_t>(std::count(before.begin(), before.end(), '\n'));
  const std::size_t last_newline = before.rfind('\n');
  const std::size_t column =
      last_newline == std::string_view::npos ? offset + 1 : offset - last_newline;
  return {line, column};
}

// nlohmann's what() is "[json.exception.parse_error.101] parse error at line 1, column 5: msg";
// keep only "msg" because we print our own position.
std::string parser_message(const json::exception& ex) {
  const std::string_view what = ex.what();
  const std::size_t head = what.find("parse error");
  const std::size_t colon = what.find(": ", head == std::string_view::npos ? 0 : head);
  if (colon == std::string_view::npos) return std::string(what);
  return std::string(what.substr(colon + 2));
}

// Builds the tree like nlohmann's own DOM parser, but knows the JSON path of every value, so it
// can report duplicate keys and out-of-range numbers where they are.
class DomBuilder final : public nlohmann::json_sax<json> {
 public:
  DomBuilder(std::string_view text, const std::string& source) : text_(text), source_(source) {}

  json take() { return std::move(root_); }

  bool null() override { return add(json(nullptr)); }
  bool boolean(bool v) override { return add(json(v)); }
  bool number_integer(number_integer_t v) override { return add(json(v)); }
  bool number_unsigned(number_unsigned_t v) override { return add(json(v)); }
  bool number_float(number_float_t v, const string_t&) override { return add(json(v)); }
  bool string(string_t& v) override { return add(json(std::move(v))); }
  bool binary(binary_t& v) override { return add(json::binary(std::move(v))); }

  bool start_object(std::size_t) override { return open(json::object()); }
  bool start_array(std::size_t) override { return open(json::array()); }
  bool end_object() override { return close(); }
  bool end_array() override { return close(); }

  bool key(string_t& k) override {
    Frame& f = stack_.back();
    if (f.container->contains(k)) {
      throw InputError(source_ + ": " + path_key(f.path, k) + ": duplicate field " +
                       single_quoted(k) + " (each field may appear only once)");
    }
    f.key = std::move(k);
    return true;
  }

  bool parse_error(std::size_t position, const std::string& last_token,
                   const nlohmann::detail::exception& ex) override {
    // `position` counts characters read, so the offending one is at position - 1.
    const auto [line, column] = line_column(text_, position == 0 ? 0 : position - 1);
    const std::string where = "line " + std::to_string(line) + ", column " + std::to_string(column);
    if (ex.id == 406) {  // number overflow: syntactically fine, but not a finite double
      throw InputError(source_ + ": " + pending_path() + ": expected a finite number, got " +
                       last_token + " (beyond the range of a double; " + where + ")");
    }
    throw InputError(source_ + ": " + where + ": " + parser_message(ex) +
                     non_finite_hint(position == 0 ? 0 : position - 1));
  }

 private:
  struct Frame {
    json* container;  // stable: only the innermost open container grows
    std::string path;
    std::string key;  // pending key when the container is an object
  };

  // People write NaN or Infinity expecting them to work; say why they do not.
  std::string non_finite_hint(std::size_t offset) const {
    std::string_view rest = text_.substr(std::min(offset, text_.size()));
    if (!rest.empty() && (rest[0] == '-' || rest[0] == '+')) rest.remove_prefix(1);
    for (std::string_view word : {"NaN", "nan", "Infinity", "inf"}) {
      if (rest.substr(0, word.size()) == word) {
        return " (JSON has no NaN or Infinity; every number must be finite)";
      }
    }
    return {};
  }

  std::string pending_path() const {
    if (stack_.empty()) return "$";
    const Frame& f = stack_.back();
    return f.container->is_array() ? path_index(f.path, f.container->size())
                                   : path_key(f.path, f.key);
  }

  json* insert(json&& v) {
    if (stack_.empty()) {
      root_ = std::move(v);
      return &root_;
    }
    Frame& f = stack_.back();
    if (f.container->is_array()) {
      f.container->push_back(std::move(v));
      return &f.container->back();
    }
    json& slot = (*f.container)[f.key];
    slot = std::move(v);
    return &slot;
  }

  bool add(json&& v) {
    insert(std::move(v));
    return true;
  }

  bool open(json&& empty) {
    std::string path = pending_path();
    json* container = insert(std::move(empty));
    stack_.push_back(Frame{container, std::move(path), {}});
    return true;
  }

  bool close() {
    stack_.pop_back();
    return true;
  }

  std::string_view text_;
  const std::string& source_;
  json root_;
  std::vector<Frame> stack_;
};

}  // namespace

bool is_identifier(std::string_view key) {
  if (key.empty() || (key[0] >= '0' && key[0] <= '9')) return false;
  return std::all_of(key.begin(), key.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
  });
}

std::string path_key(std::string_view parent, std::string_view key) {
  std::string out = parent == "$" ? std::string() : std::string(parent);
  if (is_identifier(key)) {
    if (!out.empty()) out += '.';
    out += key;
  } else {
    // Keys such as "capsule.youngs_modulus_kpa" would read as two levels with a dot.
    if (out.empty()) out = "$";
    out += "[\"";
    for (char c : key) {
      if (c == '"' || c == '\\') out += '\\';
      out += c;
    }
    out += "\"]";
  }
  return out;
}

std::string path_index(std::string_view parent, std::size_t index) {
  return std::string(parent) + "[" + std::to_string(index) + "]";
}

std::string format_number(double value) {
  if (std::isnan(value)) return "NaN";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  char buf[64];
  const auto result = std::to_chars(buf, buf + sizeof buf, value);
  return std::string(buf, result.ptr);
}

std::string describe_value(const json& value) {
  switch (value.type()) {
    case json::value_t::null:
      return "null";
    case json::value_t::boolean:
      return value.get<bool>() ? "boolean true" : "boolean false";
    case json::value_t::number_integer:
      return std::to_string(value.get<int64_t>());
    case json::value_t::number_unsigned:
      return std::to_string(value.get<uint64_t>());
    case json::value_t::number_float:
      return format_number(value.get<double>());
    case json::value_t::string: {
      const auto& s = value.get_ref<const std::string&>();
      return "string \"" + s.substr(0, kMaxQuoted) + (s.size() > kMaxQuoted ? "...\"" : "\"");
    }
    case json::value_t::array:
      if (value.empty()) return "an empty array";
      return "an array of " + std::to_string(value.size()) +
             (value.size() == 1 ? " element" : " elements");
    case json::value_t::object:
      return value.empty() ? "an empty object" : "an object";
    default:
      return "a binary value";
  }
}

std::string join_names(std::span<const std::string_view> names) {
  std::string out;
  for (std::string_view name : names) {
    if (!out.empty()) out += ", ";
    out += name;
  }
  return out;
}

json parse_json_text(std::string_view text, const std::string& source) {
  if (text.find_first_not_of(" \t\r\n") == std::string_view::npos) {
    throw InputError(source + ": $: file is empty; expected a JSON object");
  }
  DomBuilder builder(text, source);
  json::sax_parse(text.data(), text.data() + text.size(), &builder);
  return builder.take();
}

void JsonReader::fail(std::string_view path, std::string_view problem) const {
  std::string message = source_;
  message += ": ";
  message += path;
  message += ": ";
  message += problem;
  throw InputError(message);
}

void JsonReader::expect_object(const json& value, std::string_view path,
                               std::initializer_list<std::string_view> allowed) const {
  if (!value.is_object()) fail(path, "expected an object, got " + describe_value(value));
  for (const auto& [key, unused] : value.items()) {
    if (std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
      fail(path_key(path, key), "unknown field " + single_quoted(key) + "; expected one of: " +
                                    join_names({allowed.begin(), allowed.size()}));
    }
  }
}

const json* JsonReader::find(const json& object, std::string_view key) {
  const auto it = object.find(key);
  return it == object.end() ? nullptr : &*it;
}

const json& JsonReader::require(const json& object, std::string_view path, std::string_view key,
                                std::string_view what) const {
  const json* value = find(object, key);
  if (value == nullptr)
    fail(path_key(path, key), "missing required field; expected " + std::string(what));
  return *value;
}

double JsonReader::number(const json& value, std::string_view path) const {
  if (!value.is_number()) fail(path, "expected a number, got " + describe_value(value));
  const double v = value.get<double>();
  if (!std::isfinite(v)) fail(path, "expected a finite number, got " + format_number(v));
  return v;
}

double JsonReader::number_in(const json& value, std::string_view path, double lo, double hi) const {
  const double v = number(value, path);
  if (!(v >= lo && v <= hi)) {
    fail(path, "expected a number in " + format_number(lo) + ".." + format_number(hi) + ", got " +
                   format_number(v));
  }
  return v;
}

int64_t JsonReader::integer_in(const json& value, std::string_view path, int64_t lo,
                               int64_t hi) const {
  bool ok = false;
  int64_t v = 0;
  if (value.is_number_unsigned()) {
    const uint64_t u = value.get<uint64_t>();
    ok = u <= static_cast<uint64_t>(std::numeric_limits<int64_t>::max());
    v = static_cast<int64_t>(u);
  } else if (value.is_number_integer()) {
    ok = true;
    v = value.get<int64_t>();
  }
  if (!ok || v < lo || v > hi) {
    fail(path, "expected an integer in " + std::to_string(lo) + ".." + std::to_string(hi) +
                   ", got " + describe_value(value));
  }
  return v;
}

uint64_t JsonReader::unsigned_integer(const json& value, std::string_view path) const {
  if (value.is_number_unsigned()) return value.get<uint64_t>();
  if (value.is_number_integer() && value.get<int64_t>() >= 0) {
    return static_cast<uint64_t>(value.get<int64_t>());
  }
  fail(path, "expected a non-negative integer (0.." +
                 std::to_string(std::numeric_limits<uint64_t>::max()) + "), got " +
                 describe_value(value));
}

std::string JsonReader::string(const json& value, std::string_view path) const {
  if (!value.is_string()) fail(path, "expected a string, got " + describe_value(value));
  return value.get<std::string>();
}

void JsonReader::fixed_numbers(const json& value, std::string_view path, std::span<double> out,
                               std::string_view shape) const {
  if (!value.is_array() || value.size() != out.size()) {
    fail(path, "expected an array of " + std::to_string(out.size()) + " numbers " +
                   std::string(shape) + ", got " + describe_value(value));
  }
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = number(value[i], path_index(path, i));
}

const json& JsonReader::array(const json& value, std::string_view path,
                              std::string_view what) const {
  if (!value.is_array()) {
    fail(path, "expected an array of " + std::string(what) + ", got " + describe_value(value));
  }
  return value;
}

}  // namespace phaco::io
