#pragma once
// Structural changes recorded during parallel systems and applied at one sync point per frame.
//
// Parallel systems must not change table shapes while others read them, so a cut, a tear, a tet
// removal or an entity's creation is recorded here and applied in the topology phase. Each
// command carries a sort key chosen by the recorder (an element id, a tool id...). At apply time
// the per-worker buffers are merged and stably sorted by key, so the result is the same for any
// number of threads as long as keys are unique; equal keys keep worker order.
// Recording may allocate (structural changes are rare events, not per-element work).
//
// Thread-safety (issue 22), stated on every public method below as "Thread:": a CommandBuffer
// is one worker's, used by one thread at a time. CommandQueues::for_worker(w) may be called from
// every worker at once, each with its own w (the `worker` of parallel_for); pending() and apply()
// only when no system runs (the sync point).
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "engine/ecs/world.hpp"

namespace phaco {

struct Command {
  uint64_t key = 0;
  std::function<void(World&)> apply;
};

// Every method. Thread: the buffer's worker only.
class CommandBuffer {
 public:
  void push(uint64_t key, std::function<void(World&)> apply) {
    commands_.push_back({key, std::move(apply)});
  }
  // Entity creation; `init` runs right after, with the new handle, to attach components.
  void create(uint64_t key, EntityKind kind, std::string name,
              std::function<void(World&, Entity)> init = {}) {
    push(key, [kind, name = std::move(name), init = std::move(init)](World& w) {
      const Entity e = w.create(kind, name);
      if (init) init(w, e);
    });
  }
  void destroy(uint64_t key, Entity e) {
    push(key, [e](World& w) { w.destroy(e); });
  }
  template <class C>
  void add(uint64_t key, Entity e, C component) {
    push(key, [e, c = std::move(component)](World& w) mutable {
      if (w.alive(e)) w.add<C>(e, std::move(c));
    });
  }
  template <class C>
  void remove(uint64_t key, Entity e) {
    push(key, [e](World& w) { w.remove<C>(e); });
  }
  // Tombstones element `index` of entity e's SoA table component C (a stale entity is skipped).
  template <SoaTable C>
  void remove_element(uint64_t key, Entity e, uint32_t index) {
    push(key, [e, index](World& w) {
      if (C* table = w.get<C>(e)) table_remove(*table, index);
    });
  }

  size_t size() const { return commands_.size(); }
  bool empty() const { return commands_.empty(); }
  std::vector<Command>& commands() { return commands_; }
  void clear() { commands_.clear(); }

 private:
  std::vector<Command> commands_;
};

// One buffer per worker slot, so recording from parallel_for needs no lock.
class CommandQueues {
 public:
  explicit CommandQueues(int workers = 1)
      : buffers_(static_cast<size_t>(workers < 1 ? 1 : workers)) {}
  // Worker `worker`'s buffer (std::out_of_range past workers()). Thread: any worker, each with
  // its own index, concurrently.
  CommandBuffer& for_worker(int worker) { return buffers_.at(static_cast<size_t>(worker)); }
  // Thread: any (the count is fixed at construction).
  int workers() const { return static_cast<int>(buffers_.size()); }
  // Commands recorded and not yet applied. Thread: only when no system runs.
  size_t pending() const;
  // Merges in worker order, stable-sorts by key, applies, clears. Returns how many were applied.
  // Thread: only when no system runs (the sync point; it makes structural World calls).
  size_t apply(World& world);

 private:
  std::vector<CommandBuffer> buffers_;
  std::vector<Command> merged_;  // kept to reuse its capacity
};

}  // namespace phaco
