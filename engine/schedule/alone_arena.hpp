#pragma once
// Work on the calling thread alone, inside a pool of two: the parallel loops inside keep their
// chunks, so their bits, but no worker is woken or waited for. For work that measured cheaper on
// one thread (deform's team choice): on the 2-vCPU VM, waking a sleeping worker and waiting for it
// at a loop's join costs microseconds when the host puts the two vCPUs apart, as much as a small
// loop's work (docs/implicit_and_active.md, session 41).
//
// A one-slot oneTBB arena, made on first use and owned here (not thread_local), so that runtime
// state can hold it and it ends with its owner.
//
// Thread-safety: run is called by one thread at a time (the owner's); different threads may call
// it at different times.
#include <memory>
#include <type_traits>

namespace phaco {

class AloneArena {
 public:
  AloneArena();
  ~AloneArena();
  AloneArena(AloneArena&&) noexcept;
  AloneArena& operator=(AloneArena&&) noexcept;

  // Runs fn() on this thread with every nested parallel loop kept to it. Directly when the current
  // arena has a single thread anyway.
  template <class Fn>
  void run(Fn&& fn) {
    run_erased([](void* f) { (*static_cast<std::remove_reference_t<Fn>*>(f))(); },
               const_cast<void*>(static_cast<const void*>(&fn)));
  }

 private:
  void run_erased(void (*call)(void*), void* fn);
  struct Arena;
  std::unique_ptr<Arena> arena_;
};

}  // namespace phaco
