#pragma once
// The CLI tests' shared helpers: run the built `phaco` as a user would, in a fresh scratch folder.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "tests/support/shell.hpp"

namespace phaco::test {

// `phaco ARGS`, with `env` ("VAR=value ...") in front when given; exit code and output.
inline ShellResult phaco(const std::string& args, const std::string& env = "") {
  return shell(env + (env.empty() ? "" : " ") + PHACO_BIN + " " + args);
}

// An empty folder of its own for one test: <tmp>/phaco-cli-NAME-PID.
inline std::filesystem::path temp_dir(const std::string& name) {
  const std::filesystem::path d = std::filesystem::temp_directory_path() /
                                  ("phaco-cli-" + name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

inline std::string read_text(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

inline void write_text(const std::filesystem::path& file, const std::string& text) {
  std::ofstream(file, std::ios::binary) << text;
}

}  // namespace phaco::test
