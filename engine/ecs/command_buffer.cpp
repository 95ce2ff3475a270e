#include "engine/ecs/command_buffer.hpp"

#include <algorithm>

namespace phaco {

size_t CommandQueues::pending() const {
  size_t n = 0;
  for (const auto& b : buffers_) n += b.size();
  return n;
}

size_t CommandQueues::apply(World& world) {
  merged_.clear();
  for (auto& b : buffers_) {
    for (auto& c : b.commands()) merged_.push_back(std::move(c));
    b.clear();
  }
  std::stable_sort(merged_.begin(), merged_.end(),
                   [](const Command& a, const Command& b) { return a.key < b.key; });
  for (auto& c : merged_) c.apply(world);
  const size_t n = merged_.size();
  merged_.clear();
  return n;
}

}  // namespace phaco
