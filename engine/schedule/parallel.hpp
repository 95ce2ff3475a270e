#pragma once
// Data parallelism inside systems. Both helpers split [begin, end) by recursive halving until a
// piece holds at most `grain` elements (tbb::simple_partitioner), so the chunks depend only on
// (begin, end, grain), never on the number of threads or on who stole what. That is what lets
// per-chunk results be combined into a value that is bit-identical for 1 and N threads.
//
// `worker` is the calling thread's slot in the current arena, in [0, worker_count()): index
// per-worker scratch with it, but merge such scratch only where the merge does not depend on
// which worker did which chunk (e.g. integer counts, or per-element outputs). For floating-point
// sums use parallel_reduce_ordered.
#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/parallel_invoke.h>
#include <oneapi/tbb/parallel_reduce.h>
#include <oneapi/tbb/partitioner.h>
#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <cstdint>
#include <optional>
#include <type_traits>
#include <utility>

namespace phaco {

// Threads the current arena may use (the executor's `threads` inside a system).
inline int worker_count() {
  return tbb::this_task_arena::max_concurrency();
}

// Calls fn(chunk_begin, chunk_end, worker) once for every chunk of [begin, end); grain 0 counts
// as 1. A range of at most `grain` elements is one chunk whatever the thread count, so it runs
// right here, without a task: a loop below its grain pays nothing for threads it cannot use
// (measured in perf/RESULTS.md, thread scaling), and the chunks, hence the results, are the same.
template <class Fn>
void parallel_for(uint32_t begin, uint32_t end, uint32_t grain, Fn&& fn) {
  if (begin >= end) return;
  if (end - begin <= std::max<uint32_t>(grain, 1)) {
    // A thread outside any arena has no slot yet; it would take the first one on joining.
    fn(begin, end, std::max(tbb::this_task_arena::current_thread_index(), 0));
    return;
  }
  tbb::parallel_for(
      tbb::blocked_range<uint32_t>(begin, end, std::max<uint32_t>(grain, 1)),
      [&fn](const tbb::blocked_range<uint32_t>& r) {
        fn(r.begin(), r.end(), tbb::this_task_arena::current_thread_index());
      },
      tbb::simple_partitioner());
}

// Runs f and g, side by side when a worker is free (tbb::parallel_invoke); returns when both have.
template <class F, class G>
void parallel_invoke(F&& f, G&& g) {
  tbb::parallel_invoke(std::forward<F>(f), std::forward<G>(g));
}

namespace detail {

// Body for tbb::parallel_deterministic_reduce: empty until it has seen a chunk, so T needs no
// identity element.
template <class T, class Fn, class Merge>
struct OrderedReduceBody {
  Fn* chunk_fn;
  Merge* merge;
  std::optional<T> value;

  OrderedReduceBody(Fn* f, Merge* m) : chunk_fn(f), merge(m) {}
  OrderedReduceBody(OrderedReduceBody& other, tbb::split)
      : chunk_fn(other.chunk_fn), merge(other.merge) {}

  void operator()(const tbb::blocked_range<uint32_t>& r) {
    T part = (*chunk_fn)(r.begin(), r.end());
    value = value ? (*merge)(std::move(*value), std::move(part)) : std::move(part);
  }
  // `right` always covers the chunks after this body's, so merge(left, right) keeps chunk order.
  void join(OrderedReduceBody& right) {
    if (!right.value) return;
    value = value ? (*merge)(std::move(*value), std::move(*right.value)) : std::move(right.value);
  }
};

}  // namespace detail

// Returns merge(init, P) where P combines chunk_fn(b, e) of every chunk, left before right, over a
// binary tree fixed by (begin, end, grain): bit-identical for any thread count. merge should be
// associative in intent (sum, min, concatenation); it need not be commutative.
template <class T, class Fn, class Merge>
T parallel_reduce_ordered(uint32_t begin, uint32_t end, uint32_t grain, T init, Fn&& chunk_fn,
                          Merge&& merge) {
  if (begin >= end) return init;
  // One chunk: the same value the tree would give, without a task (see parallel_for).
  if (end - begin <= std::max<uint32_t>(grain, 1))
    return merge(std::move(init), chunk_fn(begin, end));
  using Body =
      detail::OrderedReduceBody<T, std::remove_reference_t<Fn>, std::remove_reference_t<Merge>>;
  Body body(&chunk_fn, &merge);
  tbb::parallel_deterministic_reduce(
      tbb::blocked_range<uint32_t>(begin, end, std::max<uint32_t>(grain, 1)), body,
      tbb::simple_partitioner());
  return merge(std::move(init), std::move(*body.value));
}

}  // namespace phaco
