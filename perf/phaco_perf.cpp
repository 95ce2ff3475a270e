// phaco-perf — the OpenPhaco performance harness.
//
//   phaco-perf foundation   mesh generation per level, empty-scene frame cost (engine foundation)
//   phaco-perf bandwidth    this machine's memory bandwidth (STREAM copy/triad, 1 and 2 threads)
//   phaco-perf membrane     issue 3: membrane step cost per level × threads × method, thread
//                           scaling, spring pass vs bandwidth, active set, Bullet btSoftBody peer,
//                           speed versus accuracy, stability map
//   phaco-perf cut          issue 4: cut and tear step cost per capsule level, cut fidelity
//                           (Hausdorff, remeshing), scripted capsulorhexis opening per level
//   phaco-perf haptics      issue 6: the 1 kHz haptic thread beside the scene, the local model
//   phaco-perf drills       issue 7: expert and novice drills, difficulty levels, comparisons
//   phaco-perf tear         issue 17: forceps force on the capsulorhexis flap against time, bands
//   phaco-perf trainer      issue 8: phaco-trainer's frame rate on the software renderer
//   phaco-perf trainer-ab   issue 24: this build's trainer against an earlier one, interleaved
//   phaco-perf sweep        issue 9: every drill at every level, thread count and method
//   phaco-perf soak         issue 18: the trainer drill after drill; memory, GL objects, haptics
//   phaco-perf nucleus      issue 19: the nucleus_removal expert per level, 1 and 2 threads
//   phaco-perf cohorts      issue 20: expert and novice cohorts per drill, AUC and cut-off
//   phaco-perf records      issue 21: 1, 4, 16 stations syncing to one PostgreSQL server at once
//   alternative,
//                           with the haptic thread beside it; the targets; the checks CI runs
//   phaco-perf all          every study above, in that order
//
// Every study takes --quick (small levels, few steps, about a minute) and --out-dir DIR (default
// the source tree's perf/), shows a progress bar on stderr, writes DIR/results/<study>.* and
// regenerates DIR/RESULTS.md from every section present.
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "engine/core/error.hpp"
#include "perf/studies.hpp"
#include "perf/sweep/sweep_point.hpp"

namespace {

namespace fs = std::filesystem;
using namespace phaco;

constexpr const char* kUsage = R"(phaco-perf — OpenPhaco performance harness

usage:
  phaco-perf <study> [--quick] [--out-dir DIR] [study options]
  phaco-perf --help

studies:
  foundation [--max-level L] [--scenario FILE] [--frames-repeat N]
      Mesh generation time and element counts for levels 0..L (default 7, quick 3), and the
      frame cost of the empty scene (default data/scenarios/empty_scene.json) at 1 and 2 threads,
      best of N runs (default 3, quick 1).
  bandwidth
      STREAM-like copy and triad at 1 and 2 threads on arrays about twice the last-level cache
      (quick: 256 MiB), and on cache-resident arrays.
  membrane [--max-level L]
      Membrane step cost for levels 0..L (default 7, quick 3) × threads 1, 2 × method; fitted
      slope; thread scaling; spring pass against the memory bandwidth; grasp with an active node
      set; Bullet btSoftBody on the same mesh; speed against accuracy; stability map.
  cut
      Cost of one cut step and one tear step on capsules of levels 0..6 (quick 3), both layouts;
      the cut's Hausdorff distance to the tool path, triangles added with and without remeshing,
      and the scripted capsulorhexis's opening (diameter, circularity, centring) per level; the
      capsulorhexis demo in the scene at levels 1..5 (quick 1..2): cut system time, physics
      rebuild after topology changes, frame time, opening.
  lens [--no-million]
      Issue 5, the lens: tetrahedral sculpting per level 0,1,2,3,5,7 (quick 0,1) x broadphase (octree,
      btDbvt) x narrowphase (centre, GJK, MPR) against the exact swept volume; simplex cells (removal,
      boundary, fragment labelling); shape matching (Horn vs polar decomposition on degenerate
      fragments, float vs double, cost per fragment, the whole-lens pass); the SPH neighbour search at
      10k, 100k and 1M particles (quick 10k; --no-million skips 1M) per cell order; the lens tools;
      the fragmenting lens per frame; the divide-and-conquer demo per level.
  haptics
      Issue 6, the 1 kHz haptic thread: beside the capsulorhexis scene in real time (60 s each, quick
      5 s) with and without real-time priority, models at 30 Hz, a 200 ms simulation stall: period,
      lateness, compute, sample-to-force latency, allocations on the haptic thread, force continuity;
      the loop alone with a busy second core; the local model's passive stiffness against the rate
      (Colgate's bound), continuity with and without the crossfade, tick cost per node count; the UDP
      bridge's round trip and silence-to-zero-force. About 4 minutes (quick about 30 s).
  drills
      Issue 7, the drills: every scripted expert and novice (data/scenarios) run to its end: score,
      missed targets, key metrics, globe rotation and port force, per-frame cost of the drill's
      systems; the capsulorhexis and sculpting experts at every difficulty level of their drill
      files; every novice against its drill's expert by dynamic time warping. About 2 minutes
      (quick: one expert and one novice per drill, one level).
  tear
      Issue 17 item 5, tear forces: the force the forceps exert on the capsulorhexis flap per frame
      for the scripted expert (standard, young and hard eyes) and novices, against the tissue bands
      (expert RMS 6-14 mN, novices 17, perforation 15-35, rim 150 +- 70); the tear resistance, RMS
      and peak while tearing, the opening. Writes results/tear_force.*. About 1 minute.
  trainer
      Issue 8, phaco-trainer under Xvfb on Mesa's software renderer at 1280x720, each drill with
      scripted hands: render frame rate and frame times, simulation rate and haptic period (and
      why a period ran long: lateness, compute, overruns), with and without rendering; then
      issue 20's scripted expert procedure (phaco-trainer --procedure) from start to end, with and
      without rendering. About 9 minutes (quick 2). Needs xvfb-run.
  trainer-ab --against OLD_TRAINER [--against-data DIR] [--label TEXT] [--variant NAME[@DRILL]=DIR]...
             [--reps N] [--seconds S] [--drill NAME]...
      Issue 24, this build's phaco-trainer against an earlier build's (a binary built from an
      older commit, reading that commit's data/ with --against-data), run as `trainer` runs each
      drill, the builds alternating run by run (ABBA) N times (default 4, S = 20 s each); each
      repetition gives a paired fps ratio, reported with its 95 % interval. A variant is this
      build reading another data folder (e.g. a drill with a body taken out; @DRILL: in that
      drill only), to tell a scene's content from the code. About 1 minute per run (default: 3 drills x 2 builds x 4 = 24 runs).
  sweep [--max-level L] [--drill NAME]... [--speedup-reps N] [--replot]
  sweep --reference [--drill NAME]... [--reference-level L] [--reference-dt-divisor K]
      Issues 9 and 17, the whole trainer under load: each drill's scripted expert run to its end
      at every resolution level 0..L (default 8: 256k capsule vertices, 1.6M lens tets; quick
      0..3), on 1 and 2 threads, each point in a process of its own with the 1 kHz haptic thread
      beside it; and each method alternative of the scene (integrators, stiffness, layout,
      active set, spring law; broadphase, narrowphase, lens model) at levels 1, 3, 5 (quick 1).
      Records frame and per-system p50/p99/max, CG iterations per stepped frame, physics refresh
      per cut (and per spring it patched), the cornea's worst cut frame, the 2-thread speed-up
      per level, haptic period and overruns, memory, and accuracy against the converged
      reference in DIR/results/sweep_reference.json (else the source tree's perf/results; falls
      back, labelled "missing" or "stale", to the default methods at the finest level); charts
      frame cost, stacked system cost, CG iterations, refresh cost (log-log slopes), speed-up
      against level, speed against accuracy (Pareto fronts), haptic period, memory; judges the
      issues' targets. Checks (exit status 1 if any fails): every point runs to its end, 1 and 2
      threads give the same state hash, the default methods never diverge and stay within their
      accuracy bounds against the run's own finest level. --speedup-reps N (default 5, quick 1):
      the capsulorhexis points on 1 and 2 threads run N times in all, the repeats last, so that
      the 2-thread speed-up is the mean of N paired runs with its 95 % interval (repeats must
      give the same state hash), listed pair by pair with where the vCPUs were: each point
      measures a cache line's round trip between its two CPUs before and after its frames. About
      25 minutes (quick about 1).
      --replot redraws the section and charts from DIR/results/sweep_points.json without
      measuring again (the figures stay those of the run that measured them).
      --reference makes DIR/results/sweep_reference.json instead: per drill, one run off the
      default path at level 8 (capsulorhexis: dt_s/4 and CG tolerance 1e-8, the methods key
      capsule.cg_tolerance; sculpting: dt_s/16; incision: dt_s/4), keyed by a hash of the recipe
      and the input files (a changed scenario makes it stale). --reference-level and
      --reference-dt-divisor change every chosen drill's recipe. About 5 minutes on an idle
      machine (11 under load). docs/perf_sweep.md says why the whole capsule
      (capsule.active_set=off) is not in it.
  nucleus [--max-level L]
      Issue 19, the nucleus_removal expert at levels 0..3 (--quick: 0..1; up to 5) on 1 and 2
      threads with the haptic thread beside it: cells, fragments and SPH pairs, frame p50/p99/max,
      the lens system's cost, the 2-thread speed-up, state hashes, and the outcome against the
      finest level run.
  cohorts [--n N] [--drill NAME]...
      Issue 20 item 4, do the scores separate skill: per drill (default all four), N scripted
      experts and N scripted novices (default 30, quick 4) replayed with hand tremor (8-12 Hz,
      RMS transverse 35 / 59 um, axial 13 / 21 um), tempo and offset variations, each run to its
      end; score distributions, ROC AUC, the contrasting-groups cut-off (Thomsen 2015) and the
      share of each cohort that passes it. Writes results/cohorts.*; with --drill, the other
      drills' rows are kept from the earlier results/cohorts.json, and the section names the run
      each drill's rows come from. Nucleus removal takes about a minute per run.
  records [--pg ADMIN_URI]
      Issue 21, 1, 4 and 16 stations (processes, 200 records each) syncing to one PostgreSQL
      server at once: records per second, batch latency p50/p99/max, every record at the centre
      once. The server is a throwaway cluster (scripts/pg_test_cluster.sh) unless --pg names an
      administrator's URI ending in /postgres?... (a database is made and dropped on it).
  soak [--seconds S]
      Issue 18, phaco-trainer left running drill after drill under Xvfb (phaco-trainer --soak):
      the three drills in turn, scripted hands, 6 simulated s each, for S wall seconds (default
      1800; quick 90). After each drill: resident memory, GL objects alive (probed with glIs*),
      haptic period p99/max. Checks (exit status 1): at least three rounds of the three drills,
      memory after the first round within 5 % of the first round's largest, and each drill
      leaving as many GL objects alive every time it runs from the second round on. Charts
      memory, GL objects and the haptic period against wall time. Needs xvfb-run.
  all
      foundation, bandwidth, membrane, cut, lens, haptics, drills, tear, trainer, sweep (not
      soak: it takes half an hour on its own).

Each study writes DIR/results/<study>.csv, .json, .md and <study>_*.png, then regenerates
DIR/RESULTS.md (DIR defaults to the source tree's perf/).
)";

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  // One sweep point in a process of its own (perf/sweep/sweep_point.hpp); not for users.
  if (!args.empty() && args[0] == "_sweep-point")
    return perf::sweep_point_main({args.begin() + 1, args.end()});
  bool regenerated = false;
  perf::StudyOptions options;
  try {
    if (args.empty() || args[0] == "--help" || args[0] == "-h") {
      std::fputs(kUsage, args.empty() ? stderr : stdout);
      return args.empty() ? 2 : 0;
    }
    const std::string cmd = args[0];
    options.out_dir = fs::path(PHACO_SOURCE_DIR) / "perf";
    for (size_t i = 1; i < args.size(); ++i) {
      if (args[i] == "--quick") {
        options.quick = true;
      } else if (args[i] == "--out-dir") {
        if (i + 1 >= args.size()) throw InputError("--out-dir needs a value");
        options.out_dir = args[++i];
      } else {
        options.extra.push_back(args[i]);
      }
    }
    fs::create_directories(options.out_dir / "results");
    if (cmd == "foundation") {
      perf::run_foundation(options);
    } else if (cmd == "bandwidth") {
      perf::run_bandwidth(options);
    } else if (cmd == "membrane") {
      perf::run_membrane(options);
    } else if (cmd == "cut") {
      perf::run_cut(options);
    } else if (cmd == "lens") {
      perf::run_lens(options);
    } else if (cmd == "haptics") {
      perf::run_haptics(options);
    } else if (cmd == "drills") {
      perf::run_drills(options);
    } else if (cmd == "tear") {
      perf::run_tear(options);
    } else if (cmd == "trainer") {
      perf::run_trainer_study(options);
    } else if (cmd == "trainer-ab") {
      perf::run_trainer_ab(options);
    } else if (cmd == "sweep") {
      perf::run_sweep(options);
    } else if (cmd == "soak") {
      perf::run_soak(options);
    } else if (cmd == "records") {
      perf::run_records(options);
    } else if (cmd == "nucleus") {
      perf::run_nucleus(options);
    } else if (cmd == "cohorts") {
      perf::run_cohorts(options);
    } else if (cmd == "all") {
      if (!options.extra.empty())
        throw InputError("all: unknown option '" + options.extra[0] + "'");
      perf::run_foundation(options);
      perf::run_bandwidth(options);
      perf::run_membrane(options);
      perf::run_cut(options);
      perf::run_lens(options);
      perf::run_haptics(options);
      perf::run_drills(options);
      perf::run_tear(options);
      perf::run_trainer_study(options);
      perf::run_sweep(options);
    } else {
      std::fprintf(stderr, "phaco-perf: unknown study '%s' (try --help)\n", cmd.c_str());
      return 2;
    }
    regenerated = true;
    perf::regenerate_results(options.out_dir);
    std::printf("wrote %s\n", (options.out_dir / "RESULTS.md").c_str());
    return 0;
  } catch (const perf::CheckFailed& e) {
    // The figures were written: keep them in RESULTS.md, then fail.
    if (!regenerated) perf::regenerate_results(options.out_dir);
    std::fprintf(stderr, "phaco-perf: check failed: %s\n", e.what());
    return 1;
  } catch (const InputError& e) {
    std::fprintf(stderr, "phaco-perf: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "phaco-perf: internal error: %s\n", e.what());
    return 1;
  }
}
