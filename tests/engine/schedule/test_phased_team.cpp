// engine/schedule/phased_team.hpp: every chunk of a phase runs once and after all of the phase
// before; the gate is asked once per phase, with every earlier write visible, and stops the team
// where it says; a team of two gives the bits of one thread; a team whose helper never joins (one
// thread in the arena) still finishes.
#include <gtest/gtest.h>
#include <oneapi/tbb/task_arena.h>

#include <atomic>
#include <cmath>
#include <cstdint>
#include <vector>

#include "engine/schedule/phased_team.hpp"

namespace phaco {
namespace {

// A chain of phases over `n` values, double-buffered: phase p reads the whole of buffer[p % 2]
// (so a chunk that ran before all of phase p − 1 had finished would read stale values) and writes
// its range of buffer[(p + 1) % 2]; the gate stops once the sum passes a limit.
struct PhaseChain {
  uint32_t n = 1000, chunks = 10;
  std::vector<double> buffer[2] = {std::vector<double>(n, 1.0), std::vector<double>(n, 0.0)};
  std::vector<uint32_t> runs_of_chunk;  // per (phase, chunk)
  std::vector<uint32_t> gate_calls;     // per phase
  double limit = 1e300;

  static double sum(const std::vector<double>& v) {
    double s = 0.0;
    for (double x : v) s += x;
    return s;
  }

  uint64_t run(PhasedTeam& team, uint64_t max_phases) {
    runs_of_chunk.assign(size_t(max_phases) * chunks, 0);
    gate_calls.assign(size_t(max_phases) + 1, 0);
    const uint32_t per = n / chunks;
    return team.run(
        chunks, max_phases,
        [&](uint64_t phase) {
          ++gate_calls[phase];
          return sum(buffer[phase % 2]) < limit;
        },
        [&](uint64_t phase, uint32_t c) {
          ++runs_of_chunk[phase * chunks + c];
          const std::vector<double>& in = buffer[phase % 2];
          std::vector<double>& out = buffer[(phase + 1) % 2];
          const double total = sum(in);
          for (uint32_t i = c * per; i < (c + 1) * per; ++i)
            out[i] = in[i] + 1e-3 * total + std::sin(double(i + phase));
        });
  }
};

TEST(PhasedTeam, EveryChunkRunsOnceAndTheGateOncePerPhase) {
  for (int threads : {1, 2}) {
    SCOPED_TRACE(threads);
    tbb::task_arena arena(threads);
    arena.execute([&] {
      PhaseChain c;
      PhasedTeam team(true);
      const uint64_t stopped = c.run(team, 40);
      EXPECT_EQ(stopped, 40u) << "no gate said stop: the limit is far";
      for (uint32_t k = 0; k < c.runs_of_chunk.size(); ++k)
        ASSERT_EQ(c.runs_of_chunk[k], 1u) << "phase " << k / c.chunks << " chunk " << k % c.chunks;
      for (uint64_t p = 0; p < 40; ++p) EXPECT_EQ(c.gate_calls[p], 1u) << p;
    });
  }
}

// Phase p's chunks read the whole vector: on two threads each reads it after all of phase p − 1
// wrote (else its sums differ from one thread's); the stopping phase is the same.
TEST(PhasedTeam, ATeamOfTwoGivesTheBitsOfOneThread) {
  std::vector<double> results[2];
  uint64_t stopped[2] = {};
  for (int threads : {1, 2}) {
    tbb::task_arena arena(threads);
    arena.execute([&] {
      PhaseChain c;
      c.limit = 5e4;  // passed after a few dozen phases
      PhasedTeam team(true);
      stopped[threads - 1] = c.run(team, 1000);
      results[threads - 1] = c.buffer[stopped[threads - 1] % 2];
      for (uint64_t p = stopped[threads - 1] + 1; p < c.gate_calls.size(); ++p)
        ASSERT_EQ(c.gate_calls[p], 0u) << "nothing runs past the stop";
    });
  }
  EXPECT_GT(stopped[0], 3u);
  EXPECT_LT(stopped[0], 1000u) << "the gate stopped the team";
  EXPECT_EQ(stopped[0], stopped[1]);
  EXPECT_EQ(results[0], results[1]);
}

// One team, several runs (as a step runs its assembly, then its solve): each run completes, and a
// team that was not wanted runs everything on the calling thread.
TEST(PhasedTeam, ServesSeveralRunsAndRunsAloneWhenNotWanted) {
  tbb::task_arena arena(2);
  arena.execute([&] {
    for (bool wanted : {true, false}) {
      PhasedTeam team(wanted);
      for (int r = 0; r < 5; ++r) {
        std::vector<std::atomic<int>> hits(64);
        const uint64_t stopped = team.run(
            64, 3, [](uint64_t) { return true; },
            [&](uint64_t, uint32_t c) { hits[c].fetch_add(1); });
        EXPECT_EQ(stopped, 3u);
        for (auto& h : hits) EXPECT_EQ(h.load(), 3);
      }
    }
  });
}

}  // namespace
}  // namespace phaco
