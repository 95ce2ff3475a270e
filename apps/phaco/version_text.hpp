#pragma once
// `phaco --version` and `phaco-trainer --version`: the version and source revision of the build
// (engine/core/version.hpp) and where the program finds its data (procedures/eye/data_dir.hpp),
// so a user, CI and a bug report can tell which build ran on which data.
#include <string>

#include "engine/core/error.hpp"
#include "engine/core/version.hpp"
#include "procedures/eye/data_dir.hpp"

namespace phaco::cli {

inline std::string version_text(const std::string& program) {
  std::string out = program + " " + version() + " (revision " + revision() + ")\n";
  try {
    const eye::DataDir d = eye::locate_data_dir();
    out += "data: " + d.dir.string() + " (" + d.origin + ")\n";
  } catch (const InputError& e) {
    out += std::string("data: not found: ") + e.what() + "\n";
  }
  return out;
}

}  // namespace phaco::cli
