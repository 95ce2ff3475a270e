#pragma once
// A SystemDesc in one call, for the schedule tests.
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "engine/schedule/system.hpp"

namespace phaco::test {

inline SystemDesc make_system(std::string name, std::vector<std::string> reads,
                              std::vector<std::string> writes,
                              std::function<void(const FrameContext&)> run) {
  SystemDesc s;
  s.name = std::move(name);
  s.reads = std::move(reads);
  s.writes = std::move(writes);
  s.run = std::move(run);
  return s;
}

}  // namespace phaco::test
