#include "perf/machine.hpp"

#include <sys/utsname.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <string>
#include <thread>

namespace phaco::perf {

Machine describe_machine() {
  Machine m;
  std::ifstream cpuinfo("/proc/cpuinfo");
  for (std::string line; std::getline(cpuinfo, line);) {
    if (line.rfind("model name", 0) == 0) {
      m.cpu = line.substr(line.find(':') + 2);
      break;
    }
  }
  m.logical_cores = static_cast<int>(std::thread::hardware_concurrency());
  m.memory_gib = static_cast<double>(sysconf(_SC_PHYS_PAGES)) *
                 static_cast<double>(sysconf(_SC_PAGE_SIZE)) / (1024.0 * 1024.0 * 1024.0);
#if defined(__clang__)
  m.compiler = std::string("clang ") + __clang_version__;
#elif defined(__GNUC__)
  m.compiler = std::string("g++ ") + __VERSION__;
#endif
#ifdef NDEBUG
  m.build = "Release (-O3, portable: no -march)";
#else
  m.build = "Debug";
#endif
  utsname u{};
  if (uname(&u) == 0) m.os = std::string(u.sysname) + " " + u.release + " " + u.machine;
  return m;
}

std::string machine_markdown(const Machine& m) {
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "| CPU | %s |\n| logical cores | %d |\n| memory | %.1f GiB |\n| compiler | %s |\n"
                "| build | %s |\n| OS | %s |\n",
                m.cpu.c_str(), m.logical_cores, m.memory_gib, m.compiler.c_str(), m.build.c_str(),
                m.os.c_str());
  return std::string("| | |\n|---|---|\n") + buf;
}

}  // namespace phaco::perf
