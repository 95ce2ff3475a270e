#pragma once
// How long before each deadline the haptic loop stops sleeping and spins (haptic_loop.hpp).
//
// The spin absorbs the kernel's wake-up latency: a sleep that returns later than the margin makes
// the tick late. That latency is not a constant of the machine. On this VM it is about 45 µs when
// the cores are idle, but with the simulation, a compiler or llvmpipe's threads on both cores a
// SCHED_FIFO thread was seen returning from its sleep over 100 µs late at the 1 % tail (the
// capsulorhexis at load 11: period p99 1037 µs with a fixed 60 µs margin, 1000.5 µs with 200 µs).
// A fixed margin large enough for the loaded machine would spin that long on every tick of an
// idle one (20 % of a core at 200 µs).
//
// So the margin follows the sleeps' observed overshoot (how late each sleep returned after the
// time it asked for): a decaying maximum, raised at once to any larger overshoot and decaying by
// a fixed fraction per tick (half-life ~0.35 s at 1 kHz), plus a guard; never below the
// configured floor, never above the cap (from the cap back to a 60 µs floor: about 0.9 s). A loaded
// machine thus gets a longer spin within a tick, and an idle one returns to the floor within a
// second or two.
//
// Plain data and arithmetic: no allocation, lock or system call (the loop's hot path).
// Thread: one thread (the loop's) owns an instance.
#include <algorithm>
#include <cstdint>

namespace phaco {

struct SpinMargin {
  int64_t floor_ns = 60'000;      // the least margin (LoopSettings::spin_ns)
  int64_t cap_ns = 250'000;       // the most (LoopSettings::max_spin_ns); = floor: a fixed margin
  int64_t guard_ns = 20'000;      // added to the worst recent overshoot
  double decay_per_tick = 0.998;  // of the remembered overshoot
  double worst_ns = 0.0;          // the decaying maximum of the sleeps' overshoot

  // The margin for the next sleep.
  int64_t margin_ns() const {
    const int64_t want = static_cast<int64_t>(worst_ns) + guard_ns;
    return std::clamp(want, floor_ns, std::max(floor_ns, cap_ns));
  }
  // A sleep asked to return at t and returned `overshoot_ns` after it (≥ 0 normally). Counted up
  // to the cap only: a longer one (the VM's core taken away for milliseconds) no spin can cover,
  // and it must not hold the margin at the cap for seconds.
  void observe_sleep(int64_t overshoot_ns) {
    const int64_t counted = std::clamp<int64_t>(overshoot_ns, 0, std::max(cap_ns, floor_ns));
    worst_ns = std::max(worst_ns, static_cast<double>(counted));
  }
  // Once per tick, slept or not.
  void decay() { worst_ns *= decay_per_tick; }
  // Starts from a margin learned before (LoopSettings::start_margin_ns, a previous loop's
  // margin_ns()): the next margin_ns() is `margin` within [floor, cap], and it decays from there
  // as a remembered overshoot would.
  void start_at(int64_t margin) {
    worst_ns = static_cast<double>(std::max<int64_t>(0, margin - guard_ns));
  }
};

}  // namespace phaco
