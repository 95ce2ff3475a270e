// The issue-9 sweep's pieces: a point's result survives the trip through the child process's JSON,
// the accuracy error is the largest relative difference of the drill's scored outcome, and a point
// run with the haptic thread beside it is bit-identical to the plain run of the same scenario; the
// speed-up pairs name where the vCPUs were, measured by a cache line's round trip.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <thread>

#include "engine/core/error.hpp"
#include "perf/cores.hpp"
#include "perf/sweep/sweep_data.hpp"
#include "perf/sweep/sweep_levels.hpp"
#include "perf/sweep/sweep_plan.hpp"
#include "perf/sweep/sweep_point.hpp"
#include "procedures/scene/run.hpp"

namespace phaco::perf {
namespace {

namespace fs = std::filesystem;

SweepPointResult with_metrics(const std::string& drill, nlohmann::json metrics) {
  SweepPointResult r;
  r.config.drill = drill;
  r.ok = true;
  r.metrics = std::move(metrics);
  return r;
}

TEST(SweepPoint, ResultRoundTripsThroughJson) {
  SweepPointResult r = with_metrics("phaco_sculpting", {{"score", 97.5}, {"tets_removed", 12}});
  r.config.scenario = "/x/phaco_sculpting_expert.json";
  r.config.level = 5;
  r.config.threads = 2;
  r.config.methods = {{"lens.broadphase", "dbvt"}};
  r.config.variant = "lens.broadphase=dbvt";
  r.frames = 6840;
  r.frame = {"frame", 0.1, 0.3, 2.5, 0.12};
  r.systems = {{"lens_sculpt", 0.05, 0.2, 1.0, 0.06}};
  r.period_p99_us = 1010.5;
  r.haptic_allocations = 0;
  r.period_bins = {{999, 1, 10}, {1000, 1, 900}};
  r.elements = {{"lens.tets", 100}, {"lens.particles", 40}};
  r.total_elements = 140;
  r.bytes_per_element = 180.5;
  r.state_hash = "0123456789abcdef";
  const SweepPointResult back = result_from_json(nlohmann::json::parse(to_json(r).dump()));
  EXPECT_EQ(back.config.variant, r.config.variant);
  EXPECT_EQ(back.config.methods, r.config.methods);
  EXPECT_EQ(back.config.level, 5);
  EXPECT_EQ(back.config.threads, 2);
  EXPECT_EQ(back.frames, 6840u);
  EXPECT_DOUBLE_EQ(back.frame.max_ms, 2.5);
  ASSERT_EQ(back.systems.size(), 1u);
  EXPECT_EQ(back.systems[0].name, "lens_sculpt");
  EXPECT_DOUBLE_EQ(back.period_p99_us, 1010.5);
  EXPECT_EQ(back.period_bins, r.period_bins);
  EXPECT_EQ(back.elements, r.elements);
  EXPECT_DOUBLE_EQ(back.bytes_per_element, 180.5);
  EXPECT_EQ(back.state_hash, r.state_hash);
  EXPECT_DOUBLE_EQ(drill_elements(back), 112.0);  // tets left plus those the probe removed
  EXPECT_TRUE(std::isnan(back.round_trip_before_ns)) << "not measured: null, read back as NaN";
  r.round_trip_before_ns = 131.5, r.round_trip_after_ns = 462.0;
  const SweepPointResult measured = result_from_json(nlohmann::json::parse(to_json(r).dump()));
  EXPECT_DOUBLE_EQ(measured.round_trip_before_ns, 131.5);
  EXPECT_DOUBLE_EQ(measured.round_trip_after_ns, 462.0);
}

TEST(SweepAccuracy, LargestRelativeDifferenceOfTheScoredOutcome) {
  const auto ref =
      with_metrics("capsulorhexis", {{"rhexis.diameter_mm", 5.0}, {"rhexis.circularity", 0.95}});
  const auto run = with_metrics("capsulorhexis",
                                {{"rhexis.diameter_mm", 4.5}, {"rhexis.circularity", 0.95 * 1.02}});
  std::string detail;
  EXPECT_NEAR(accuracy_error_pct(run, ref, &detail), 10.0, 1e-9);
  EXPECT_NE(detail.find("rhexis.diameter_mm"), std::string::npos);
  EXPECT_DOUBLE_EQ(accuracy_error_pct(ref, ref), 0.0);
  // An incomplete rhexis has no diameter: the error is unknown, never 0.
  const auto open = with_metrics("capsulorhexis", {{"rhexis.circularity", 0.9}});
  EXPECT_TRUE(std::isnan(accuracy_error_pct(open, ref, &detail)));
  EXPECT_NE(detail.find("missing"), std::string::npos);
}

// The haptic thread beside the frames (scripted device, models published each frame) must not
// change the run: the same state hash as run_scenario's.
TEST(SweepPoint, TheHapticThreadBesideLeavesTheRunBitIdentical) {
  const fs::path scenario =
      fs::path(PHACO_SOURCE_DIR) / "data/scenarios/corneal_incision_expert.json";
  SweepPointConfig c;
  c.drill = "corneal_incision";
  c.scenario = scenario;
  c.level = 0;
  c.threads = 2;
  c.realtime = false;  // a test must not ask for SCHED_FIFO
  const SweepPointResult r = run_sweep_point(c);
  ASSERT_TRUE(r.ok) << r.error;
  Scenario s = load_scenario(scenario);
  s.eye.level = 0;
  const RunReport plain = run_scenario(s, SceneOptions{.threads = 1});
  EXPECT_EQ(r.state_hash, plain.state_hash);
  EXPECT_EQ(r.frames, plain.frames);
  EXPECT_LE(r.frame.p50_ms, r.frame.p99_ms);
  EXPECT_LE(r.frame.p99_ms, r.frame.max_ms);
  EXPECT_GT(r.total_elements, 0u);
  EXPECT_GT(r.rss_peak_mb, 0.0);
  EXPECT_GE(r.rss_peak_mb, r.rss_before_mb);
  EXPECT_TRUE(r.metrics.contains("incision.width_mm"));
}

// A point whose process fails or dies is a failed point with the reason, and the sweep goes on.
TEST(SweepPoint, AChildThatFailsOrCrashesIsReportedNotFatal) {
  const fs::path dir =
      fs::temp_directory_path() / ("phaco_sweep_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  SweepPointConfig c;
  c.drill = "corneal_incision";
  c.scenario = "/nonexistent/scenario.json";
  const fs::path fail = dir / "fail.sh", crash = dir / "crash.sh";
  std::ofstream(fail) << "#!/bin/sh\necho 'no such mesh' >&2\nexit 3\n";
  std::ofstream(crash) << "#!/bin/sh\nkill -SEGV $$\n";
  fs::permissions(fail, fs::perms::owner_all);
  fs::permissions(crash, fs::perms::owner_all);
  const SweepPointResult failed = run_sweep_point_isolated(c, fail, dir / "a");
  EXPECT_FALSE(failed.ok);
  EXPECT_NE(failed.error.find("exited with status 3: no such mesh"), std::string::npos)
      << failed.error;
  const SweepPointResult died = run_sweep_point_isolated(c, crash, dir / "b");
  EXPECT_FALSE(died.ok);
  EXPECT_NE(died.error.find("signal 11"), std::string::npos) << died.error;
  // In this process: the bad scenario is an input error naming the file.
  c.haptics = false;
  try {
    run_sweep_point(c);
    ADD_FAILURE() << "no error for a missing scenario";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/scenario.json"), std::string::npos)
        << e.what();
  }
  fs::remove_all(dir);
}

// The child's own entry point: an input it cannot read as a point's configuration (empty, not
// JSON, a field of the wrong type or missing) is exit status 2 and a line naming the file, not an
// uncaught exception; no result file is written.
TEST(SweepPoint, AnUnreadableConfigurationIsAnErrorNotACrash) {
  const fs::path dir =
      fs::temp_directory_path() / ("phaco_sweep_cfg_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path out = dir / "out.json";
  for (const std::string text : {"", "{not json", "[]", R"({"drill": 1})", R"({"drill": "x"})"}) {
    SCOPED_TRACE(text);
    const fs::path in = dir / "in.json";
    std::ofstream(in) << text;
    EXPECT_EQ(sweep_point_main({in.string(), out.string()}), 2);
    EXPECT_FALSE(fs::exists(out));
  }
  EXPECT_EQ(sweep_point_main({(dir / "missing.json").string(), out.string()}), 2);
  EXPECT_EQ(sweep_point_main({"only-one-argument"}), 2);
  fs::remove_all(dir);
}

// The baseline the accuracy target compares with: missing is no baseline; present but unreadable
// is an input error naming the file (the study's "internal error" before).
TEST(SweepLevels, AnUnreadableBaselineIsNamed) {
  const fs::path dir =
      fs::temp_directory_path() / ("phaco_sweep_base_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  EXPECT_TRUE(load_baseline(dir / "missing.json").points.empty());
  for (const std::string text : {"{not json", R"({"points": [{"drill": "capsulorhexis"}]})"}) {
    SCOPED_TRACE(text);
    std::ofstream(dir / "baseline.json") << text;
    try {
      load_baseline(dir / "baseline.json");
      ADD_FAILURE() << "no error";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("baseline.json"), std::string::npos) << e.what();
    }
  }
  fs::remove_all(dir);
}

// The 2-thread speed-up over repeated pairs (issue 17 item 7): the plan runs the capsulorhexis
// default points again at its end, thread order alternating, each repeat keyed as the default
// point (its state hash must match); a level's speed-up is the mean of its paired ratios.
TEST(SweepSpeedup, RepeatsArePlannedLastAndAveragedPairByPair) {
  SweepRun run;
  run.max_level = 1;
  run.drills = {"capsulorhexis", "corneal_incision"};
  run.threads = {1, 2};
  run.variant_levels = {};
  run.speedup_reps = 3;
  const SweepPlan plan = plan_sweep(run, true, "/scenarios", "/cache");
  std::vector<const SweepPointConfig*> repeats;
  size_t first_repeat = plan.points.size();
  for (size_t i = 0; i < plan.points.size(); ++i)
    if (is_repeat_variant(plan.points[i].variant)) {
      repeats.push_back(&plan.points[i]);
      first_repeat = std::min(first_repeat, i);
    }
  ASSERT_EQ(repeats.size(), 2u * 2u * 2u);  // repeats 2 and 3 × levels 0, 1 × 1 and 2 threads
  EXPECT_EQ(plan.points.size() - first_repeat, repeats.size());  // all after the other points
  for (const SweepPointConfig* c : repeats) {
    EXPECT_EQ(c->drill, "capsulorhexis");
    SweepPointConfig plain = *c;
    plain.variant = "default";
    EXPECT_EQ(point_key(*c), point_key(plain));
  }
  EXPECT_EQ(repeats[0]->variant, "repeat 2");
  EXPECT_EQ(repeats[0]->threads, 2);  // repeat 2 starts with 2 threads, repeat 3 with 1
  EXPECT_EQ(repeats[4]->variant, "repeat 3");
  EXPECT_EQ(repeats[4]->threads, 1);

  // Three pairs at level 0 with ratios 1.2, 1.5 and 1.8: the mean 1.5 and Student's interval.
  std::vector<SweepRow> rows;
  auto add = [&](const std::string& variant, int threads, double mean_ms) {
    SweepRow row;
    row.r = with_metrics("capsulorhexis", {{"score", 90.0}});
    row.r.config.level = 0, row.r.config.threads = threads, row.r.config.variant = variant;
    row.r.frame.mean_ms = mean_ms;
    rows.push_back(row);
  };
  add("default", 1, 1.2), add("default", 2, 1.0);
  add("repeat 2", 2, 1.0), add("repeat 2", 1, 1.5);
  add("repeat 3", 1, 1.8), add("repeat 3", 2, 1.0);
  const std::vector<LevelFigures> figs = level_figures(rows, "capsulorhexis", 0);
  ASSERT_EQ(figs.size(), 1u);
  EXPECT_EQ(figs[0].speedup_pairs, 3);
  EXPECT_NEAR(figs[0].speedup, 1.5, 1e-12);
  EXPECT_NEAR(figs[0].speedup_hi - 1.5, 4.303 * 0.3 / std::sqrt(3.0), 1e-9);
  EXPECT_NEAR(figs[0].mean_1, 1.2, 1e-12);  // the frame columns are the first pair's
  EXPECT_NE(speedup_text(figs[0]).find("], 3"), std::string::npos) << speedup_text(figs[0]);
}

// Each pair is listed with where the 2-thread point's vCPUs were, and the pairs' median speed-up is
// given per placement.
TEST(SweepSpeedup, PairsAreListedWithWhereTheVcpusWere) {
  std::vector<SweepRow> rows;
  auto add = [&](const std::string& variant, int threads, double mean_ms, double before,
                 double after, double team) {
    SweepRow row;
    row.r = with_metrics("capsulorhexis", {{"score", 90.0}});
    row.r.config.level = 6, row.r.config.threads = threads, row.r.config.variant = variant;
    row.r.frame.mean_ms = mean_ms;
    row.r.round_trip_before_ns = before, row.r.round_trip_after_ns = after;
    row.r.physics["capsule"] = {{"team_steps", team}};
    rows.push_back(row);
  };
  const double kNaN = std::numeric_limits<double>::quiet_NaN();
  add("default", 1, 1.10, 130, 135, 0), add("default", 2, 1.00, 120, 140, 692);      // near: 1.10
  add("repeat 2", 2, 1.00, 450, 470, 37), add("repeat 2", 1, 0.97, 455, 460, 0);     // apart: 0.97
  add("repeat 3", 1, 1.20, 130, 460, 0), add("repeat 3", 2, 1.00, 130, 460, 400);    // moved: 1.20
  add("repeat 4", 1, 0.99, 440, 450, 0), add("repeat 4", 2, 1.00, 440, 450, 40);     // apart: 0.99
  add("repeat 5", 1, 1.00, kNaN, kNaN, 0), add("repeat 5", 2, 1.00, kNaN, kNaN, 9);  // unknown
  EXPECT_EQ(placement_of(rows[1].r), Placement::Near);
  EXPECT_EQ(placement_of(rows[2].r), Placement::Apart);
  EXPECT_EQ(placement_of(rows[5].r), Placement::Moved);
  EXPECT_EQ(placement_of(rows[9].r), Placement::Moved) << "not measured";
  const std::string md = speedup_pairs_md(rows, 8);
  EXPECT_NE(md.find("| 6 | 1.10× (near 120/140 ns, 692 team), 0.97× (apart 450/470 ns, 37 team)"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("near: 1 pairs, median 1.10×"), std::string::npos) << md;
  EXPECT_NE(md.find("apart: 2 pairs, median 0.98× (0.97–0.99×)"), std::string::npos) << md;
  EXPECT_NE(md.find("moved: 2 pairs"), std::string::npos) << md;
  EXPECT_EQ(speedup_pairs_md({}, 8), "");
}

// A cache line's round trip: a positive figure between two CPUs, none where the thread may run on
// one only.
TEST(Cores, RoundTripIsMeasuredBetweenTwoCpusOnly) {
  const int first = two_cpus().first;
  if (first < 0) {  // this machine gives the test one CPU
    EXPECT_TRUE(std::isnan(core_round_trip_ns(3, 1000)));
    return;
  }
  // A figure, not a speed: how fast the trip is belongs to bench_engine and the sweep.
  const double ns = core_round_trip_ns(3, 1000);
  EXPECT_TRUE(std::isfinite(ns));
  EXPECT_GT(ns, 0.0);
  std::thread([first] {
    {
      const PinnedScope one(first);
      ASSERT_TRUE(one.pinned());
      EXPECT_EQ(two_cpus().first, -1);
      EXPECT_TRUE(std::isnan(core_round_trip_ns(3, 1000)));
    }
    EXPECT_EQ(two_cpus().first, first) << "the scope gave the thread its CPUs back";
  }).join();
}

}  // namespace
}  // namespace phaco::perf
