#pragma once
// Runs a FrameGraph once per frame on a oneTBB arena of a fixed number of threads. The flow graph
// (one continue_node per system, one edge per dependency) is built once in the constructor; a frame
// is "put a message into every root, wait for all", with no allocation of its own.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "engine/schedule/frame_graph.hpp"

namespace phaco {

struct SystemTiming {
  std::string name;
  std::vector<float> samples_ms;  // one wall-time sample per frame, ms

  // Nearest-rank percentile, p in [0, 100]; 0 when there are no samples.
  double percentile_ms(double p) const;
  double p50_ms() const { return percentile_ms(50); }
  double p99_ms() const { return percentile_ms(99); }
};

// Whether the executor tracks running systems' access and aborts on a race (AccessTracker).
// BuildDefault: on when engine/schedule was compiled without NDEBUG.
enum class AccessCheck : uint8_t { BuildDefault, On, Off };

// How a frame's systems reach the threads.
//   Graph:  the flow graph; independent systems run side by side.
//   Serial: one topological order on the calling thread (parallel loops inside a system still
//           use the arena's workers).
//   Auto:   Graph while the systems' costs are unknown (the first frames) or while running the
//           independent branches side by side is predicted to save more than dispatch_cost_ms;
//           otherwise Serial. The prediction is the work off the critical path, from a moving
//           average of each system's time. Handing a 20 us system to a sleeping worker costs
//           more than it saves, and a frame that is one long system gains nothing from it.
// Any topological order gives the same state (frame_graph.hpp), so the choice never changes a
// result, only where the time goes.
enum class Dispatch : uint8_t { Auto, Graph, Serial };

struct ExecutorSettings {
  AccessCheck access_check = AccessCheck::BuildDefault;
  Dispatch dispatch = Dispatch::Auto;
  // What waking a worker and handing it a branch costs, ms (measured on the 2-core CI machine:
  // perf/RESULTS.md, "Frame dispatch").
  double dispatch_cost_ms = 0.05;
};

// Thread-safety (issue 22), stated on every public method below as "Thread:": an Executor is
// driven by one thread (the simulation's). run_frame is not reentrant and must not overlap
// another call on the same executor; the systems it runs may use parallel_for inside its task
// arena. The getters read what the last run_frame left: call them from the driving thread between
// frames. Two executors on two threads are independent.
class Executor {
 public:
  // threads >= 1 (std::invalid_argument otherwise). The graph must outlive the executor.
  // Thread: any; the executor then belongs to the thread that drives it.
  Executor(const FrameGraph& graph, int threads, AccessCheck check = AccessCheck::BuildDefault);
  Executor(const FrameGraph& graph, int threads, const ExecutorSettings& settings);
  Executor(FrameGraph&&, int, AccessCheck = AccessCheck::BuildDefault) = delete;
  Executor(FrameGraph&&, int, const ExecutorSettings&) = delete;
  ~Executor();
  Executor(const Executor&) = delete;
  Executor& operator=(const Executor&) = delete;

  // Runs every system once, concurrently where the graph allows, and returns when all have
  // finished. A system's exception is rethrown here after the frame has drained; the executor
  // stays usable. Thread: the driving thread; not reentrant (a system must not call it).
  void run_frame(const FrameContext& ctx);

  // Fixed at construction. Thread: any.
  int threads() const;
  // Fixed at construction. Thread: any.
  bool checks_access() const;
  // Frames run through the flow graph and serially so far (Auto's choices; for the harness).
  // Thread: the driving thread, between frames.
  uint64_t graph_frames() const;
  uint64_t serial_frames() const;
  // Thread: any (the graph is immutable).
  const FrameGraph& graph() const;

  // One per system, in graph order. Thread: the driving thread, between frames (run_frame
  // appends to them).
  const std::vector<SystemTiming>& timings() const;
  // The whole run_frame. Thread: as timings().
  const SystemTiming& frame_timing() const;
  // Keeps run_frame allocation-free for the next `frames` frames. Thread: the driving thread,
  // between frames.
  void reserve_frames(size_t frames);
  // Thread: the driving thread, between frames.
  void clear_timings();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace phaco
