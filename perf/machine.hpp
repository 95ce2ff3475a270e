#pragma once
// What machine a figure was measured on: CPU model, cores, memory, compiler, build flags.
#include <string>

namespace phaco::perf {

struct Machine {
  std::string cpu;
  int logical_cores = 0;
  double memory_gib = 0;
  std::string compiler;
  std::string build;
  std::string os;
};

Machine describe_machine();
std::string machine_markdown(const Machine& m);

}  // namespace phaco::perf
