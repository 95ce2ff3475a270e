#include "engine/schedule/executor.hpp"

#include <oneapi/tbb/flow_graph.h>
#include <oneapi/tbb/global_control.h>
#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cassert>
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

// Dispatch::Auto's moving average of a system's time: about the last eight frames.
constexpr double kCostSmoothing = 1.0 / 8.0;

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
  ExecutorSettings settings;
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

  // Dispatch: a topological order for serial frames, each system's smoothed cost (written only by
  // the node that runs it), and the critical path's scratch, sized once.
  std::vector<uint32_t> order;
  std::vector<double> cost_ms;
  std::vector<double> finish_ms;
  bool costs_known = false;
  uint64_t graph_frames = 0;
  uint64_t serial_frames = 0;
#ifndef NDEBUG
  // Set while run_frame runs (it is not reentrant; executor.hpp).
  std::atomic<bool> in_frame{false};
#endif

  Impl(const FrameGraph& g, int n, const ExecutorSettings& s)
      : graph(g), threads(n), settings(s), parallelism(raise_parallelism(n)), arena(n) {}

  // Kahn's algorithm, lowest index first: `after` may point backwards, so graph order is not
  // always a topological one.
  void build_order() {
    std::vector<uint32_t> waiting = graph.predecessor_counts();
    order.clear();
    for (size_t i = 0; i < graph.size(); ++i)
      if (waiting[i] == 0) order.push_back(static_cast<uint32_t>(i));
    for (size_t k = 0; k < order.size(); ++k) {
      for (uint32_t s : graph.successors()[order[k]])
        if (--waiting[s] == 0) order.push_back(s);
    }
    cost_ms.assign(graph.size(), 0.0);
    finish_ms.assign(graph.size(), 0.0);
  }

  // Whether this frame goes through the flow graph (see Dispatch).
  bool use_graph() {
    switch (settings.dispatch) {
      case Dispatch::Graph:
        return true;
      case Dispatch::Serial:
        return false;
      case Dispatch::Auto:
        break;
    }
    if (threads < 2) return false;
    if (!costs_known) return true;
    // Longest path through the graph weighted by each system's smoothed cost; the rest of the
    // work is what a second thread could take off the frame.
    double total = 0, critical = 0;
    std::fill(finish_ms.begin(), finish_ms.end(), 0.0);
    for (uint32_t i : order) {
      const double done = finish_ms[i] + cost_ms[i];
      total += cost_ms[i];
      critical = std::max(critical, done);
      for (uint32_t s : graph.successors()[i]) finish_ms[s] = std::max(finish_ms[s], done);
    }
    return total - critical > settings.dispatch_cost_ms;
  }

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
    // Only node i touches timings[i] and cost_ms[i], once per frame, so no lock is needed.
    const float ms = elapsed_ms(t0, Clock::now());
    timings[i].samples_ms.push_back(ms);
    cost_ms[i] = costs_known ? cost_ms[i] + kCostSmoothing * (ms - cost_ms[i]) : ms;
  }
};

Executor::Executor(const FrameGraph& graph, int threads, AccessCheck check)
    : Executor(graph, threads, ExecutorSettings{.access_check = check}) {}

Executor::Executor(const FrameGraph& graph, int threads, const ExecutorSettings& settings) {
  if (threads < 1) {
    throw std::invalid_argument("Executor: threads must be at least 1, got " +
                                std::to_string(threads));
  }
  if (!(settings.dispatch_cost_ms >= 0)) {
    throw std::invalid_argument("Executor: dispatch_cost_ms must be finite and >= 0");
  }
  impl_ = std::make_unique<Impl>(graph, threads, settings);
  Impl& im = *impl_;
  im.build_order();
  const AccessCheck check = settings.access_check;
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
#ifndef NDEBUG
  // A frame overlapping another (a system calling run_frame, or a second thread) would run the
  // systems twice at once over the same components, and overwrite im.ctx under the first.
  [[maybe_unused]] const bool overlapping = im.in_frame.exchange(true);
  assert(!overlapping && "Executor::run_frame is not reentrant");
  struct Leave {
    std::atomic<bool>& flag;
    ~Leave() { flag.store(false); }
  } leave{im.in_frame};
#endif
  const Clock::time_point t0 = Clock::now();
  im.ctx = ctx;
  if (!im.use_graph()) {
    ++im.serial_frames;
    // Inside the arena, so that a system's parallel loops still reach its workers.
    im.arena.execute([&im] {
      try {
        for (uint32_t i : im.order) im.run_system(i);
      } catch (...) {
        if (im.tracker) im.tracker->clear();
        throw;
      }
    });
    im.costs_known = true;
    im.frame.samples_ms.push_back(elapsed_ms(t0, Clock::now()));
    return;
  }
  ++im.graph_frames;
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
  im.costs_known = true;
  im.frame.samples_ms.push_back(elapsed_ms(t0, Clock::now()));
}

int Executor::threads() const {
  return impl_->threads;
}
bool Executor::checks_access() const {
  return impl_->tracker.has_value();
}
uint64_t Executor::graph_frames() const {
  return impl_->graph_frames;
}
uint64_t Executor::serial_frames() const {
  return impl_->serial_frames;
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
