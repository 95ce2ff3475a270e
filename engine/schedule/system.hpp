#pragma once
// A system described as data: what it is called, when in the frame it belongs, which components it
// reads and writes, and the function that does the work. The scheduler derives the whole per-frame
// task graph from these descriptions (engine/schedule/frame_graph.hpp); nothing else orders
// systems.
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace phaco {

// The frame's phases in DESIGN.md §4 order. A phase only says which of two systems is "earlier";
// systems of different phases that share no component still run concurrently.
enum class Phase : uint8_t { Input, Contacts, Topology, Dynamics, Publish, Metrics };

inline constexpr int kPhaseCount = 6;

constexpr std::string_view to_string(Phase phase) {
  switch (phase) {
    case Phase::Input:
      return "input";
    case Phase::Contacts:
      return "contacts";
    case Phase::Topology:
      return "topology";
    case Phase::Dynamics:
      return "dynamics";
    case Phase::Publish:
      return "publish";
    case Phase::Metrics:
      return "metrics";
  }
  return "unknown";
}

// What every system sees of the frame it runs in.
struct FrameContext {
  uint64_t frame = 0;  // frame number, 0-based
  double time_s = 0;   // simulated time at the start of the frame, s
  double dt_s = 0;     // simulated step, s
};

struct SystemDesc {
  std::string name;  // unique within a graph
  Phase phase = Phase::Dynamics;
  std::vector<std::string> reads;  // component names, e.g. "capsule.particles", "tools.pose"
  std::vector<std::string> writes;
  std::vector<std::string> after;  // extra explicit ordering: run after these systems (by name)
  bool barrier = false;  // a sync point: after every earlier system, before every later one
  std::function<void(const FrameContext&)> run;
};

}  // namespace phaco
