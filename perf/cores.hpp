#pragma once
// Which CPUs a measuring thread runs on, and how far apart two of them are. A 2-thread figure on
// a VM depends on where the host puts its vCPUs: on session 40's 2-vCPU VM a cache line's round
// trip between them moved within minutes between 440–480 ns (apart) and 112–117 ns (near), and a
// team of two threads paid in the second case only (docs/implicit_and_active.md). The sweep
// records the round trip beside each point (docs/perf_sweep.md), bench_engine measures it as a
// benchmark, and the haptics study pins its load threads.
#include <sched.h>

#include <atomic>
#include <thread>
#include <utility>

namespace phaco::perf {

// The lowest and highest CPU the calling thread may run on; (-1, -1) with fewer than two.
std::pair<int, int> two_cpus();

// Pins the calling thread to one CPU for the scope (cpu < 0: leaves it as it is) and gives it back
// its previous set after. Best effort: pinned() says whether it took.
class PinnedScope {
 public:
  explicit PinnedScope(int cpu);
  ~PinnedScope();
  PinnedScope(const PinnedScope&) = delete;
  PinnedScope& operator=(const PinnedScope&) = delete;
  bool pinned() const { return ok_; }

 private:
  cpu_set_t old_{};
  bool ok_ = false;
};

// A thread pinned to `cpu` that sends a ball (a cache line) back each time the caller sends it:
// trip() is one round trip between the caller's CPU and that one.
// Thread-safety: trip() from one thread.
class RoundTripPartner {
 public:
  explicit RoundTripPartner(int cpu);
  ~RoundTripPartner();
  RoundTripPartner(const RoundTripPartner&) = delete;
  RoundTripPartner& operator=(const RoundTripPartner&) = delete;
  void trip() {
    ball_.store(served_, std::memory_order_release);
    while (ball_.load(std::memory_order_acquire) != served_ + 1) {
    }
    served_ += 2;
  }

 private:
  alignas(64) std::atomic<int64_t> ball_{0};
  alignas(64) std::atomic<bool> done_{false};
  int64_t served_ = 1;
  std::thread partner_;
};

// The median over `batches` batches of `trips` round trips between two_cpus()' two CPUs, ns per
// round trip; NaN where the thread may run on fewer than two CPUs. About batches × trips × 0.5 µs.
double core_round_trip_ns(int batches = 9, int trips = 4000);

}  // namespace phaco::perf
