#include "engine/schedule/alone_arena.hpp"

#include <oneapi/tbb/task_arena.h>

#include "engine/schedule/parallel.hpp"

namespace phaco {

struct AloneArena::Arena {
  tbb::task_arena arena{1, 1};  // one slot, taken by the caller: no worker
};

AloneArena::AloneArena() = default;
AloneArena::~AloneArena() = default;
AloneArena::AloneArena(AloneArena&&) noexcept = default;
AloneArena& AloneArena::operator=(AloneArena&&) noexcept = default;

void AloneArena::run_erased(void (*call)(void*), void* fn) {
  if (worker_count() < 2) {
    call(fn);
    return;
  }
  if (!arena_) arena_ = std::make_unique<Arena>();
  arena_->arena.execute([&] { call(fn); });
}

}  // namespace phaco
