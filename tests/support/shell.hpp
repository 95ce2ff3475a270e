#pragma once
// Running a command line from a test, as a user would in a shell: exit code and the combined
// stdout + stderr.
#include <sys/wait.h>

#include <cstdio>
#include <string>

namespace phaco::test {

struct ShellResult {
  int code = -1;       // exit code; −1 when the command did not exit normally
  std::string output;  // stdout and stderr together
};

inline ShellResult shell(const std::string& command) {
  ShellResult r;
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return r;
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, pipe)) > 0) r.output.append(buf, n);
  const int status = pclose(pipe);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

}  // namespace phaco::test
