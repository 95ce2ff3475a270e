#pragma once
// Whether the implicit step's team of two threads pays, decided by timing both ways (issue 17).
//
// The team (engine/schedule/phased_team.hpp) hands a phase from thread to thread several times
// per CG iteration, so what it gains depends on where the two threads run, and on this 2-vCPU VM
// that changed within minutes as the host moved the vCPUs: a core-to-core round trip of
// 440–480 ns (cores apart), 112–117 ns (cores near) or 70–80 ns (two hardware threads of one
// core), per perf/benchmarks/bench_engine BM_CoreRoundTrip. The capsulorhexis expert at level 6,
// frame mean on 2 threads beside the haptic thread: the team 1.08–1.12× as fast as 1 thread with
// the cores near, 0.7–0.8× with them apart (docs/implicit_and_active.md, "Session 40"). No fixed
// size threshold is right in every placement, so each size class keeps its recent steps' costs
// with and without the team, takes the cheaper, and tries the other now and then.
//
// The choice moves work between threads, never a result: the team's sums run in chunk order
// whoever runs a chunk, so 1 and 2 threads give the same bits whichever way a step went.
#include <array>
#include <cstdint>

namespace phaco::deform {

struct TeamChoice {
  // The last few steps' costs one way, per node and CG iteration (ns). The way's cost is their
  // least: a step is only ever slowed by what else ran (the haptic thread, the host), never sped
  // up, so the least of a few is the way's own cost, and a way whose cost rises loses its old
  // low figures within a few steps.
  struct Recent {
    std::array<double, 8> ns{};
    uint32_t steps = 0;  // recorded so far, up to UINT32_MAX (the ring holds min(steps, 8))
    uint32_t next = 0;   // the ring's slot for the next step
    double least() const;
  };
  struct SizeClass {
    Recent alone, team;
    uint32_t since_trial = 0;       // steps since the costlier way was last tried
    uint32_t retrial_interval = 0;  // steps between retrials now (0: rule.retrial_every)
    bool team_was_cheaper = false;  // whether the team was the cheaper way at the last choice
  };
  // By ⌊log2 nodes⌋ − 8: 256–511 nodes, 512–1023, ..., the last class everything larger.
  std::array<SizeClass, 8> classes{};
};

// Thresholds of the choice. 256 nodes is ImplicitSettings::cg_team_min_rows, below which a team
// was never formed. 4 trials each way fill half of each ring before the least is trusted. Then
// the costlier way is retried after 32 steps, and each retrial that leaves the choice as it was
// doubles the wait, up to 256 steps; a turned choice brings the wait back to 32. With the vCPUs
// apart, a retrial every 32 steps put 38–71 (once 181, once 199) of the level-0 expert's steps
// on a team that lost: 2 threads 0.93× as fast as 1 (median of 11 triples); with the waits
// doubling, 14–38 (once 79, once 110) and 0.99×. Neutral at level 6, where session 41 had tried
// it (docs/implicit_and_active.md, "Session 43"). A move of the vCPUs is still followed within
// 256 steps (tests TeamChoice.*).
struct TeamChoiceRule {
  uint32_t min_nodes = 256;     // below: the calling thread alone, untimed
  uint32_t trial_steps = 4;     // steps each way before the cheaper is taken
  uint32_t retrial_every = 32;  // then the costlier way after this many steps ...
  uint32_t retrial_most = 256;  // ... the wait doubling while the choice holds, up to this
};

// Should a step over `nodes` nodes run on the team? false below rule.min_nodes.
// Thread: the step's (the cache's owner).
bool choose_team(TeamChoice& choice, uint32_t nodes, const TeamChoiceRule& rule = {});

// The step's measured cost: wall time of its assembly and solve over nodes × (iterations + 2).
// Thread: the step's.
void record_team_step(TeamChoice& choice, uint32_t nodes, bool on_team, double ns_per_node_it,
                      const TeamChoiceRule& rule = {});

}  // namespace phaco::deform
