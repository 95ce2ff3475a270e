#pragma once
// Option parsing shared by the `phaco` subcommands: options of the form --name VALUE, flags, and
// everything else positional. Unknown options are bad input (exit code 2), named in the message.
// (A copy of the helper in commands.cpp, made shareable for records_commands.cpp.)
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "engine/core/error.hpp"

namespace phaco::cli {

struct Args {
  std::vector<std::string> positional;
  std::vector<std::pair<std::string, std::string>> options;
  std::vector<std::string> flags;

  std::optional<std::string> option(const std::string& name) const {
    for (const auto& [k, v] : options) {
      if (k == name) return v;
    }
    return std::nullopt;
  }
  bool flag(const std::string& name) const {
    return std::find(flags.begin(), flags.end(), name) != flags.end();
  }
};

// Writes `text` to `path`; InputError naming the file when it cannot.
inline void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path);
  if (!out) throw InputError("cannot write '" + path.string() + "'");
  out << text;
  if (!out.flush()) throw InputError("cannot write '" + path.string() + "'");
}

inline Args parse_args(const std::string& command, const std::vector<std::string>& raw,
                       const std::vector<std::string>& valued,
                       const std::vector<std::string>& flags,
                       const std::string& help = "phaco --help") {
  Args a;
  for (size_t i = 0; i < raw.size(); ++i) {
    const std::string& s = raw[i];
    if (s.rfind("--", 0) != 0) {
      a.positional.push_back(s);
    } else if (std::find(valued.begin(), valued.end(), s) != valued.end()) {
      if (i + 1 >= raw.size()) throw InputError(command + ": option " + s + " needs a value");
      a.options.push_back({s, raw[++i]});
    } else if (std::find(flags.begin(), flags.end(), s) != flags.end()) {
      a.flags.push_back(s);
    } else {
      throw InputError(command + ": unknown option '" + s + "' (try '" + help + "')");
    }
  }
  return a;
}

}  // namespace phaco::cli
