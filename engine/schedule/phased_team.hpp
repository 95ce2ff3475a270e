#pragma once
// A sequence of short phases worked by a team: the calling thread plus, if the arena has one, a
// worker that joins. Made for iterative solvers whose every step is a handful of microseconds
// (one CG iteration over a few hundred nodes): a parallel_for per step pays a task spawn and a
// join each time, more than the step itself. Here the team is formed once per solve, and the
// threads move from phase to phase on shared counters.
//
//   phase 0:  caller → [c0 c1 c2 c3 c4 c5] ← helper      (chunks = 6)
//   phase 1:  caller → [c0 c1 c2 c3 c4 c5] ← helper      (opens when all of phase 0 is done)
//
// The thread that finishes the last chunk of a phase asks gate(next phase) whether to go on and
// opens it; the threads then claim its chunks, the caller from the front and the helper from the
// back (so each keeps to the same rows, in its own cache), and run work(phase, chunk) on each. No
// chunk is bound to a thread: a helper that joins late (or never) leaves more chunks to the
// caller, which alone can finish every phase. So a phase's result does not depend on who ran
// which chunk, and a solver that sums per-chunk partials in chunk order gets the same bits on any
// number of threads.
//
// gate(phase) is asked once per phase, while no chunk runs: it reads what the earlier phases
// wrote; returning false stops the team. run_phases returns the phase whose gate said stop (or
// `max_phases`).
//
// Thread-safety: run_phases is called by one thread; work(phase, chunk) runs concurrently for the
// chunks of one phase (they must write disjoint data), never across phases; gate never runs
// concurrently with work or with itself. Call it inside a task arena (the executor's) for a
// worker to join; outside one it runs on the calling thread.
#include <oneapi/tbb/task_arena.h>
#include <oneapi/tbb/task_group.h>

#include <atomic>
#include <cstdint>
#include <thread>
#include <utility>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

namespace phaco {

namespace detail {

inline void spin_pause(uint32_t round) {
  // Spin while a phase ends (microseconds); yield once it takes longer, so a thread that lost its
  // core (to the haptic thread, or another process) gets it back.
  if (round < 4096) {
#if defined(__x86_64__) || defined(__i386__)
    _mm_pause();
#endif
  } else {
    std::this_thread::yield();
  }
}

constexpr uint64_t kRunning = ~uint64_t(0);
struct PhaseCounters {
  // Which chunks of the current phase are taken: (phase + 1) << 32 | taken from the front << 16 |
  // taken from the back. One word, so that a claim is one compare-and-swap.
  alignas(64) std::atomic<uint64_t> claims{0};
  alignas(64) std::atomic<uint64_t> done{0};    // chunks finished, over all phases
  alignas(64) std::atomic<uint64_t> opened{0};  // phase p may run once opened > p
  alignas(64) std::atomic<uint64_t> stop_phase{kRunning};
};

// Claims the next chunk of `phase` from the front (the calling thread) or the back (the helper);
// returns false once the phase's chunks are all taken. Each thread thus keeps to its end of the
// rows from phase to phase, and its rows stay in its own cache.
inline bool claim_chunk(PhaseCounters& c, uint64_t phase, uint32_t chunks, bool front,
                        uint32_t& chunk) {
  uint64_t word = c.claims.load(std::memory_order_relaxed);
  for (;;) {
    const uint64_t word_phase = word >> 32;  // phase + 1; 0 before the first claim
    uint32_t taken_front = 0, taken_back = 0;
    if (word_phase == phase + 1) {
      taken_front = uint32_t(word >> 16) & 0xffffu, taken_back = uint32_t(word) & 0xffffu;
    } else if (word_phase > phase + 1) {
      return false;  // a later phase is running: this one is over
    }
    if (taken_front + taken_back >= chunks) return false;
    chunk = front ? taken_front : chunks - 1 - taken_back;
    const uint64_t next = (phase + 1) << 32 | uint64_t(taken_front + (front ? 1 : 0)) << 16 |
                          uint64_t(taken_back + (front ? 0 : 1));
    // Relaxed: a claim orders nothing; the phase's inputs are ordered by `opened` (acquire).
    if (c.claims.compare_exchange_weak(word, next, std::memory_order_relaxed)) return true;
  }
}

// Asks the gate once per phase, by the one thread that finished the phase before (or the caller
// for phase 0): nothing else runs then, so the gate reads settled data, and no thread ever asks
// it about a phase that others have moved past.
template <class Gate>
void open_phase(PhaseCounters& c, uint64_t phase, uint64_t max_phases, Gate& gate) {
  // Release: a thread that sees the phase opened (or the team stopped) sees what this one saw.
  if (phase >= max_phases || !gate(phase))
    c.stop_phase.store(phase, std::memory_order_release);
  else
    c.opened.store(phase + 1, std::memory_order_release);
}

template <class Gate, class Work>
void work_phases(PhaseCounters& c, uint32_t chunks, uint64_t max_phases, bool front, Gate& gate,
                 Work& work) {
  // A helper that joins late starts at the newest open phase.
  const uint64_t opened = c.opened.load(std::memory_order_acquire);
  for (uint64_t phase = opened == 0 ? 0 : opened - 1;; ++phase) {
    for (uint32_t round = 0;; ++round) {
      // Acquire pairs with open_phase's release: the earlier phases' writes are visible.
      if (c.stop_phase.load(std::memory_order_acquire) != kRunning) return;
      if (c.opened.load(std::memory_order_acquire) > phase) break;
      spin_pause(round);
    }
    uint32_t chunk = 0;
    while (claim_chunk(c, phase, chunks, front, chunk)) {
      work(phase, chunk);
      // acq_rel: the thread that counts the phase's last chunk sees every chunk's writes.
      if (c.done.fetch_add(1, std::memory_order_acq_rel) + 1 == (phase + 1) * chunks)
        open_phase(c, phase + 1, max_phases, gate);
    }
  }
}

}  // namespace detail

// The calling thread and (if the arena has a second thread) one worker, held for a few phased
// runs. Form it before the serial work that precedes the runs: the worker wakes and joins while
// the caller is still busy, where waking a sleeping worker at the start of a run can take as long
// as the run (measured on the 2-core VM: a level-3 solve of 0.5 ms often ended before it arrived).
// Until it is given a run, and between runs, the helper spins (then yields), so hold a team only
// around work that needs it: the worker does nothing else meanwhile.
//
// Runs phases 0, 1, 2, ... of `chunks` chunks each (1 ≤ chunks < 65536) until gate(phase)
// returns false or max_phases have run; the caller takes chunks from the front, the helper from
// the back. Two threads at most: the machines this is made for have two cores, and two ends are
// what keeps each thread on its own rows. Without a helper the calling thread runs every chunk in
// order; the results are the same. run returns the phase that stopped.
//
// Thread-safety: construct, run and destroy on one thread.
class PhasedTeam {
 public:
  explicit PhasedTeam(bool wanted) {
    if (!wanted || tbb::this_task_arena::max_concurrency() < 2) return;
    has_helper_ = true;
    helper_.run([this] { help(); });
  }
  ~PhasedTeam() {
    if (!has_helper_) return;
    released_.store(true, std::memory_order_release);
    helper_.wait();  // runs help() here if no worker took it: it sees the release and returns
  }
  PhasedTeam(const PhasedTeam&) = delete;
  PhasedTeam& operator=(const PhasedTeam&) = delete;

  template <class Gate, class Work>
  uint64_t run(uint32_t chunks, uint64_t max_phases, Gate&& gate, Work&& work) {
    detail::PhaseCounters counters;
    if (chunks == 0) chunks = 1;
    detail::open_phase(counters, 0, max_phases, gate);
    if (!has_helper_) {
      detail::work_phases(counters, chunks, max_phases, true, gate, work);
      return counters.stop_phase.load(std::memory_order_acquire);
    }
    auto helper_side = [&] {
      detail::work_phases(counters, chunks, max_phases, false, gate, work);
    };
    job_ = {[](void* side) { (*static_cast<decltype(helper_side)*>(side))(); }, &helper_side};
    // Release: the helper that takes the job sees it and the opened phase 0.
    state_.store(kPosted, std::memory_order_release);
    detail::work_phases(counters, chunks, max_phases, true, gate, work);
    // Close the job; if the helper took it, wait until it has left: counters and job live here.
    uint32_t expected = kPosted;
    if (!state_.compare_exchange_strong(expected, kIdle, std::memory_order_acq_rel)) {
      for (uint32_t round = 0; state_.load(std::memory_order_acquire) != kFinished; ++round)
        detail::spin_pause(round);
      state_.store(kIdle, std::memory_order_relaxed);
    }
    return counters.stop_phase.load(std::memory_order_acquire);
  }

 private:
  enum : uint32_t { kIdle, kPosted, kTaken, kFinished };
  struct Job {
    void (*run)(void*) = nullptr;
    void* side = nullptr;
  };

  void help() {
    for (uint32_t round = 0;; ++round) {
      if (released_.load(std::memory_order_acquire)) return;
      uint32_t expected = kPosted;
      if (state_.load(std::memory_order_relaxed) == kPosted &&
          state_.compare_exchange_strong(expected, kTaken, std::memory_order_acq_rel)) {
        job_.run(job_.side);
        state_.store(kFinished, std::memory_order_release);  // the caller may now return
        round = 0;
        continue;
      }
      detail::spin_pause(round);
    }
  }

  bool has_helper_ = false;
  Job job_;
  alignas(64) std::atomic<uint32_t> state_{kIdle};
  alignas(64) std::atomic<bool> released_{false};
  tbb::task_group helper_;
};

// One phased run on a team formed for it (see PhasedTeam; `team` false: the caller alone).
template <class Gate, class Work>
uint64_t run_phases(uint32_t chunks, uint64_t max_phases, bool team, Gate&& gate, Work&& work) {
  PhasedTeam t(team);
  return t.run(chunks, max_phases, std::forward<Gate>(gate), std::forward<Work>(work));
}

}  // namespace phaco
