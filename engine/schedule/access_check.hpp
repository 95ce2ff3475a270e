#pragma once
// Runtime guard behind the static guarantee of FrameGraph: while systems run, it keeps, per
// component, who is writing it and how many are reading it, and reports the first system that
// starts touching a component in a way that races with a system already running (write/write or
// read/write). A correct graph and executor never trip it; it catches executor bugs and systems
// whose run function was swapped for one with different access. Costs one mutex per system start
// and end, so the executor enables it in debug builds (or on request), not on the release path.
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "engine/schedule/frame_graph.hpp"

namespace phaco {

struct AccessConflict {
  size_t running = 0;   // system already running
  size_t starting = 0;  // system whose start was refused
  uint32_t component = 0;
  bool both_write = false;  // false: one reads what the other writes
};

class AccessTracker {
 public:
  explicit AccessTracker(const FrameGraph& graph);

  // Marks `system` as running. On a conflict nothing is marked and the conflict is returned.
  std::optional<AccessConflict> try_enter(size_t system);
  // As try_enter, but prints describe() to stderr and aborts on a conflict.
  void enter(size_t system);
  void exit(size_t system);
  // Forgets every running system (after a frame aborted by an exception).
  void clear();

  std::string describe(const AccessConflict& conflict) const;

 private:
  static constexpr uint32_t kNoWriter = UINT32_MAX;

  const FrameGraph& graph_;
  std::mutex mutex_;
  std::vector<uint32_t> writer_;   // per component: running writer or kNoWriter
  std::vector<uint32_t> readers_;  // per component: number of running readers
  std::vector<uint8_t> running_;   // per system
};

}  // namespace phaco
