#include "engine/schedule/access_check.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>

namespace phaco {

AccessTracker::AccessTracker(const FrameGraph& graph)
    : graph_(graph),
      writer_(graph.components().size(), kNoWriter),
      readers_(graph.components().size(), 0),
      running_(graph.size(), 0) {}

std::optional<AccessConflict> AccessTracker::try_enter(size_t system) {
  std::lock_guard lock(mutex_);
  for (uint32_t c : graph_.write_ids(system)) {
    if (writer_[c] != kNoWriter) return AccessConflict{writer_[c], system, c, true};
    if (readers_[c] > 0) {
      // Name one running reader (not the starting system itself: reading and writing one's own
      // component is allowed).
      for (size_t s = 0; s < running_.size(); ++s) {
        const auto& r = graph_.read_ids(s);
        if (running_[s] && s != system && std::binary_search(r.begin(), r.end(), c)) {
          return AccessConflict{s, system, c, false};
        }
      }
    }
  }
  for (uint32_t c : graph_.read_ids(system)) {
    if (writer_[c] != kNoWriter) return AccessConflict{writer_[c], system, c, false};
  }
  for (uint32_t c : graph_.write_ids(system)) writer_[c] = static_cast<uint32_t>(system);
  for (uint32_t c : graph_.read_ids(system)) ++readers_[c];
  running_[system] = 1;
  return std::nullopt;
}

void AccessTracker::enter(size_t system) {
  if (auto conflict = try_enter(system)) {
    std::fprintf(stderr, "phaco schedule: %s\n", describe(*conflict).c_str());
    std::abort();
  }
}

void AccessTracker::exit(size_t system) {
  std::lock_guard lock(mutex_);
  if (!running_[system]) return;
  for (uint32_t c : graph_.write_ids(system)) writer_[c] = kNoWriter;
  for (uint32_t c : graph_.read_ids(system)) --readers_[c];
  running_[system] = 0;
}

void AccessTracker::clear() {
  std::lock_guard lock(mutex_);
  std::fill(writer_.begin(), writer_.end(), kNoWriter);
  std::fill(readers_.begin(), readers_.end(), 0);
  std::fill(running_.begin(), running_.end(), 0);
}

std::string AccessTracker::describe(const AccessConflict& conflict) const {
  const std::string& running = graph_.system(conflict.running).name;
  const std::string& starting = graph_.system(conflict.starting).name;
  const std::string& component = graph_.components()[conflict.component];
  return "access conflict on '" + component + "': system '" + starting + "' started while '" +
         running + "' was running and " +
         (conflict.both_write ? std::string("both write it")
                              : std::string("one writes what the other reads")) +
         "; declare the access in both systems' reads/writes so the graph orders them";
}

}  // namespace phaco
