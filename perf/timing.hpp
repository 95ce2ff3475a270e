#pragma once
// Timing helpers for the studies: best-of-repeats time per call, run inside a oneTBB arena of a
// given number of threads (so parallel_for inside the call uses exactly that many).
#include <oneapi/tbb/task_arena.h>

#include <algorithm>

#include "engine/core/clock.hpp"

namespace phaco::perf {

// Calls fn() repeatedly for at least min_seconds (and at least min_calls times), `repeats` times;
// returns the smallest mean seconds per call among the repeats. When the warm-up call alone
// exceeds min_seconds, one more call is timed and that is the figure.
template <class Fn>
double seconds_per_call(int threads, double min_seconds, int repeats, Fn&& fn, int min_calls = 3) {
  tbb::task_arena arena(std::max(threads, 1));
  double best = 1e300;
  arena.execute([&] {
    Stopwatch warm;
    fn();  // warm-up: caches, page faults, TBB workers started
    // A call slower than the whole budget (an implicit solve on a large mesh) is timed once more.
    if (warm.elapsed_s() > min_seconds) repeats = 1, min_calls = 1;
    for (int r = 0; r < std::max(repeats, 1); ++r) {
      Stopwatch clock;
      long calls = 0;
      do {
        fn();
        ++calls;
      } while (calls < min_calls || clock.elapsed_s() < min_seconds);
      best = std::min(best, clock.elapsed_s() / static_cast<double>(calls));
    }
  });
  return best;
}

// Runs fn() once inside an arena of `threads` threads; returns the wall time in seconds.
template <class Fn>
double seconds_once(int threads, Fn&& fn) {
  tbb::task_arena arena(std::max(threads, 1));
  double s = 0;
  arena.execute([&] {
    Stopwatch clock;
    fn();
    s = clock.elapsed_s();
  });
  return s;
}

}  // namespace phaco::perf
