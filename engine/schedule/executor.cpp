#include "engine/schedule/executor.hpp"

#include <oneapi/tbb/flow_graph.h>
#include <oneapi/tbb/global_control.h>
#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <stdexcept>

#include "engine/core/access_scope.hpp"
#include "engine/schedule/access_check.hpp"

namespace phaco {
namespace {

#ifdef NDEBUG
constexpr bool kCheckAccessByDefault = false;
#else
constexpr bool kCheckAccessByDefault = true;
#endif

// Enough for a minute at 120 Hz before any timing vector grows.
constexpr size_t kInitialFrameCapacity = 8192;

using Clock = std::chrono::steady_clock;
using Node = tbb::flow::continue_node<tbb::flow::continue_msg>;

float elapsed_ms(Clock::time_point t0, Clock::time_point t1) {
  return std::chrono::duration<float, std::milli>(t1 - t0).count();
}

// A system's declared reads and writes, against which its World lookups are checked while it
// runs (engine/core/access_scope.hpp).
class DeclaredAccess final : public AccessScope {
 public:
  explicit DeclaredAccess(const SystemDesc& s) : system_(&s) {}
  void touch(std::string_view access_name) const override {
    for (const auto* list : {&system_->reads, &system_->writes})
      for (const std::string& n : *list)
        if (n == access_name) return;
    throw std::logic_error("system '" + system_->name + "' touched '" + std::string(access_name) +
                           "' without declaring it in its reads or writes");
  }

 private:
  const SystemDesc* system_;
};

}  // namespace

double SystemTiming::percentile_ms(double p) const {
  if (samples_ms.empty()) return 0.0;
  std::vector<float> sorted = samples_ms;
  const double n = static_cast<double>(sorted.size());
  const double rank = std::ceil(std::clamp(p, 0.0, 100.0) / 100.0 * n);
  const size_t k = static_cast<size_t>(std::clamp(rank, 1.0, n)) - 1;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(k), sorted.end());
  return sorted[k];
}

struct Executor::Impl {
  // Members die in reverse order: nodes unregister from the flow graph first, then the flow graph
  // (which waits inside the arena), the arena last.
  const FrameGraph& graph;
  int threads;
  // oneTBB caps workers at the core count; asking for more threads than cores (a determinism
  // test on 4 threads on a 2-core machine) must really get them, so the cap is raised while
  // this executor lives.
  std::unique_ptr<tbb::global_control> parallelism;
  tbb::task_arena arena;
  std::optional<tbb::flow::graph> flow;
  std::vector<std::unique_ptr<Node>> nodes;
  std::vector<uint32_t> roots;
  std::vector<SystemTiming> timings;
  SystemTiming frame;
  std::optional<AccessTracker> tracker;
  std::vector<DeclaredAccess> declared;  // per system, where access is checked
  FrameContext ctx;  // the running frame's context; written before any node is released

  Impl(const FrameGraph& g, int n)
      : graph(g), threads(n), parallelism(raise_parallelism(n)), arena(n) {}

  static std::unique_ptr<tbb::global_control> raise_parallelism(int n) {
    const auto limit =
        tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism);
    if (static_cast<size_t>(n) <= limit) return nullptr;
    return std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                 static_cast<size_t>(n));
  }

  void run_system(size_t i) {
    const SystemDesc& s = graph.system(i);
    // Leaves the tracker even when the system throws, so the next frame starts clean.
    struct TrackerExit {
      AccessTracker* tracker;
      size_t system;
      ~TrackerExit() {
        if (tracker) tracker->exit(system);
      }
    };
    AccessTracker* t = tracker ? &*tracker : nullptr;
    if (t) t->enter(i);
    TrackerExit leave{t, i};
    const AccessScopeGuard scope(declared.empty() ? nullptr : &declared[i]);
    const Clock::time_point t0 = Clock::now();
    s.run(ctx);
    // Only node i touches timings[i], and once per frame, so no lock is needed.
    timings[i].samples_ms.push_back(elapsed_ms(t0, Clock::now()));
  }
};

Executor::Executor(const FrameGraph& graph, int threads, AccessCheck check) {
  if (threads < 1) {
    throw std::invalid_argument("Executor: threads must be at least 1, got " +
                                std::to_string(threads));
  }
  impl_ = std::make_unique<Impl>(graph, threads);
  Impl& im = *impl_;
  const bool checking =
      check == AccessCheck::On || (check == AccessCheck::BuildDefault && kCheckAccessByDefault);
  if (checking) {
    const auto conflicts = graph.write_conflicts();
    if (!conflicts.empty()) {
      std::fprintf(stderr,
                   "phaco schedule: systems '%s' and '%s' write a common component "
                   "but the graph does not order them\n",
                   graph.system(conflicts[0].first).name.c_str(),
                   graph.system(conflicts[0].second).name.c_str());
      std::abort();
    }
    im.tracker.emplace(graph);
    for (size_t i = 0; i < graph.size(); ++i) im.declared.emplace_back(graph.system(i));
  }

  im.timings.resize(graph.size());
  for (size_t i = 0; i < graph.size(); ++i) im.timings[i].name = graph.system(i).name;
  im.frame.name = "frame";
  reserve_frames(kInitialFrameCapacity);

  im.arena.initialize();
  // The flow graph attaches to the arena it is created in, so build it inside ours.
  im.arena.execute([&] {
    im.flow.emplace();
    im.nodes.reserve(graph.size());
    for (size_t i = 0; i < graph.size(); ++i) {
      im.nodes.push_back(std::make_unique<Node>(*im.flow, [&im, i](const tbb::flow::continue_msg&) {
        im.run_system(i);
        return tbb::flow::continue_msg();
      }));
    }
    for (size_t p = 0; p < graph.size(); ++p) {
      for (uint32_t s : graph.successors()[p]) tbb::flow::make_edge(*im.nodes[p], *im.nodes[s]);
    }
  });
  for (size_t i = 0; i < graph.size(); ++i) {
    if (graph.predecessor_counts()[i] == 0) im.roots.push_back(static_cast<uint32_t>(i));
  }
}

Executor::~Executor() {
  if (!impl_) return;
  // Nodes and the flow graph are torn down inside the arena they were built in.
  impl_->arena.execute([this] {
    impl_->nodes.clear();
    impl_->flow.reset();
  });
}

void Executor::run_frame(const FrameContext& ctx) {
  Impl& im = *impl_;
  const Clock::time_point t0 = Clock::now();
  im.ctx = ctx;
  im.arena.execute([&im] {
    for (uint32_t r : im.roots) im.nodes[r]->try_put(tbb::flow::continue_msg());
    try {
      im.flow->wait_for_all();
    } catch (...) {
      // A cancelled frame leaves continue_nodes half counted; reset them for the next frame.
      im.flow->reset();
      if (im.tracker) im.tracker->clear();
      throw;
    }
  });
  im.frame.samples_ms.push_back(elapsed_ms(t0, Clock::now()));
}

int Executor::threads() const {
  return impl_->threads;
}
bool Executor::checks_access() const {
  return impl_->tracker.has_value();
}
const FrameGraph& Executor::graph() const {
  return impl_->graph;
}
const std::vector<SystemTiming>& Executor::timings() const {
  return impl_->timings;
}
const SystemTiming& Executor::frame_timing() const {
  return impl_->frame;
}

void Executor::reserve_frames(size_t frames) {
  for (SystemTiming& t : impl_->timings) t.samples_ms.reserve(t.samples_ms.size() + frames);
  impl_->frame.samples_ms.reserve(impl_->frame.samples_ms.size() + frames);
}

void Executor::clear_timings() {
  for (SystemTiming& t : impl_->timings) t.samples_ms.clear();
  impl_->frame.samples_ms.clear();
}

}  // namespace phaco
