#pragma once
// Checked reading of JSON input files (scenarios, eye parameters, drills). Every error names the
// file, the JSON path of the offending value and what was expected versus found:
//   scen.json: hands.left.track[3].t: track not sorted in time: expected t > 2, got 1.5
// so a person can fix the file without reading our code. Paths use dots for object fields,
// [i] for array elements, ["a.b"] for keys that are not plain identifiers, and `$` for the root.
#include <cstdint>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <string_view>
#include <utility>

namespace phaco::io {

// Path of field `key` inside the object at `parent` ("$" + "drill" -> "drill").
std::string path_key(std::string_view parent, std::string_view key);
// Path of element `index` inside the array at `parent` ("hands.left.track" + 3 -> "...track[3]").
std::string path_index(std::string_view parent, std::size_t index);

// [A-Za-z_][A-Za-z0-9_]*: keys that print as `.key` in a path.
bool is_identifier(std::string_view key);

// Shortest text that reads back to the same double; "NaN", "inf", "-inf" for non-finite values.
std::string format_number(double value);
// What a value is, for "got ..." in messages: `string "abc"`, `-1`, `an array of 2 elements`.
std::string describe_value(const nlohmann::json& value);
// "a, b, c" — for "expected one of: ..." lists.
std::string join_names(std::span<const std::string_view> names);

// Parses JSON text into a tree. Throws InputError:
//   syntax errors           "SOURCE: line L, column C: <parser message>"
//   duplicate object keys   "SOURCE: PATH: duplicate field 'k'" (nlohmann would keep the last one
//                           silently, and a silently ignored field is a typo that passes)
//   numbers beyond double   "SOURCE: PATH: expected a finite number, got 1e999 (...)"
//   empty or blank text     "SOURCE: $: file is empty; expected a JSON object"
nlohmann::json parse_json_text(std::string_view text, const std::string& source);

// Typed access to a parsed tree; each accessor throws InputError "SOURCE: PATH: PROBLEM".
class JsonReader {
 public:
  explicit JsonReader(std::string source) : source_(std::move(source)) {}

  const std::string& source() const { return source_; }

  [[noreturn]] void fail(std::string_view path, std::string_view problem) const;

  // `value` must be an object whose keys are all in `allowed`.
  void expect_object(const nlohmann::json& value, std::string_view path,
                     std::initializer_list<std::string_view> allowed) const;
  // Field `key` of `object`, or nullptr when absent.
  static const nlohmann::json* find(const nlohmann::json& object, std::string_view key);
  // Field `key` of `object`; a missing field fails with "missing required field; expected <what>".
  const nlohmann::json& require(const nlohmann::json& object, std::string_view path,
                                std::string_view key, std::string_view what) const;

  double number(const nlohmann::json& value, std::string_view path) const;  // finite
  // Finite number in [lo, hi].
  double number_in(const nlohmann::json& value, std::string_view path, double lo, double hi) const;
  int64_t integer_in(const nlohmann::json& value, std::string_view path, int64_t lo,
                     int64_t hi) const;
  uint64_t unsigned_integer(const nlohmann::json& value, std::string_view path) const;
  std::string string(const nlohmann::json& value, std::string_view path) const;
  // Array of exactly out.size() finite numbers; `shape` names them in messages ("[x, y, z]").
  void fixed_numbers(const nlohmann::json& value, std::string_view path, std::span<double> out,
                     std::string_view shape) const;
  // `value` must be an array; `what` names its elements in messages ("track samples").
  const nlohmann::json& array(const nlohmann::json& value, std::string_view path,
                              std::string_view what) const;

 private:
  std::string source_;
};

}  // namespace phaco::io
