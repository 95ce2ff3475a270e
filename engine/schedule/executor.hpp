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

class Executor {
 public:
  // threads >= 1 (std::invalid_argument otherwise). The graph must outlive the executor.
  Executor(const FrameGraph& graph, int threads, AccessCheck check = AccessCheck::BuildDefault);
  Executor(FrameGraph&&, int, AccessCheck = AccessCheck::BuildDefault) = delete;
  ~Executor();
  Executor(const Executor&) = delete;
  Executor& operator=(const Executor&) = delete;

  // Runs every system once, concurrently where the graph allows, and returns when all have
  // finished. A system's exception is rethrown here after the frame has drained; the executor
  // stays usable.
  void run_frame(const FrameContext& ctx);

  int threads() const;
  bool checks_access() const;
  const FrameGraph& graph() const;

  const std::vector<SystemTiming>& timings() const;  // one per system, in graph order
  const SystemTiming& frame_timing() const;          // the whole run_frame
  // Keeps run_frame allocation-free for the next `frames` frames.
  void reserve_frames(size_t frames);
  void clear_timings();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace phaco
