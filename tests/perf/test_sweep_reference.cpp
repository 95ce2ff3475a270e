// The issue-17 sweep pieces: the converged reference is made off the default path and the scene
// really runs it that way (finer level, smaller dt, tighter CG tolerance); its key goes stale
// when an input changes; every point's error is taken against it; and the per-level figures
// (CG iterations per step, speed-up, slopes, the Pareto reading) come out of the points.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "engine/core/error.hpp"
#include "perf/report.hpp"
#include "perf/sweep/sweep_levels.hpp"
#include "perf/sweep/sweep_mechanics.hpp"
#include "perf/sweep/sweep_reference.hpp"
#include "procedures/eye/eye_params.hpp"
#include "procedures/scene/capsule_physics.hpp"
#include "procedures/scene/run.hpp"
#include "systems/deform/implicit.hpp"

namespace phaco::perf {
namespace {

namespace fs = std::filesystem;

SweepRow row_of(const std::string& drill, int level, int threads, nlohmann::json metrics,
                const std::string& variant = "default") {
  SweepRow row;
  row.r.config.drill = drill;
  row.r.config.level = level;
  row.r.config.threads = threads;
  row.r.config.variant = variant;
  row.r.ok = true;
  row.r.metrics = std::move(metrics);
  return row;
}

nlohmann::json rhexis(double diameter, double circularity) {
  return {{"rhexis.diameter_mm", diameter}, {"rhexis.circularity", circularity}};
}

fs::path temp_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / (name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

TEST(SweepReference, TheCapsulorhexisReferenceIsOffTheDefaultPath) {
  const ReferenceRecipe recipe = default_reference_recipe("capsulorhexis");
  const SweepPointConfig ref = reference_config(recipe, "/x/capsulorhexis_expert.json", "/cache");
  const SweepPointConfig plain;       // what a default sweep point runs
  EXPECT_GT(ref.level, plain.level);  // finer than the default level 3
  EXPECT_GT(ref.dt_divisor, 1);
  EXPECT_EQ(plain.dt_divisor, 1);
  EXPECT_LT(std::stod(ref.methods.at("capsule.cg_tolerance")),
            deform::ImplicitSettings{}.cg_tolerance);
  EXPECT_EQ(plain.methods.count("capsule.cg_tolerance"), 0u);
  EXPECT_FALSE(ref.haptics);
  EXPECT_EQ(ref.threads, 1);
  // The description the report prints names each departure, the whole capsule included when a
  // recipe asks for it.
  ReferenceRecipe whole = recipe;
  whole.methods["capsule.active_set"] = "off";
  const std::string d = describe(whole);
  EXPECT_NE(d.find("level 8"), std::string::npos);
  EXPECT_NE(d.find("active_set=off"), std::string::npos);
  EXPECT_NE(d.find("dt/8"), std::string::npos);
  EXPECT_NE(d.find("CG tolerance 1e-8"), std::string::npos);
  EXPECT_EQ(reference_config(whole, "/x", "/c").methods.at("capsule.active_set"), "off");
}

// The scene reads the tolerance key (capsule_physics.cpp) and rejects a bad one.
TEST(SweepReference, TheSceneTakesTheCgToleranceFromMethods) {
  Scenario s = load_scenario(eye::data_dir() / "scenarios" / "capsulorhexis_expert.json");
  s.eye.level = 0;
  s.methods["capsule.cg_tolerance"] = "1e-9";
  SceneOptions options;
  if (const char* c = std::getenv("PHACO_CACHE_DIR")) options.cache_dir = c;
  auto scene = build_scene(s, options);
  const CapsuleSolver& cp = scene->world.at<CapsuleSolver>(*scene->body(BodyPart::Capsule));
  EXPECT_DOUBLE_EQ(cp.state.implicit.settings.cg_tolerance, 1e-9);
  s.methods["capsule.cg_tolerance"] = "tight";
  EXPECT_THROW(build_scene(s, options), InputError);
  s.methods["capsule.cg_tolerance"] = "2";
  EXPECT_THROW(build_scene(s, options), InputError);
}

// dt_divisor runs the same tracks at a smaller step: k times the frames, the same simulated time.
TEST(SweepReference, ASmallerStepRunsTheSameTracksInMoreFrames) {
  SweepPointConfig c;
  c.drill = "corneal_incision";
  c.scenario = eye::data_dir() / "scenarios" / "corneal_incision_expert.json";
  c.level = 0;
  c.haptics = false;
  if (const char* e = std::getenv("PHACO_CACHE_DIR")) c.cache_dir = e;
  const SweepPointResult one = run_sweep_point(c);
  c.dt_divisor = 3;
  const SweepPointResult three = run_sweep_point(c);
  ASSERT_TRUE(one.ok && three.ok);
  EXPECT_NEAR(double(three.frames), 3.0 * double(one.frames), 3.0);
  EXPECT_NEAR(three.sim_s, one.sim_s, 0.02);
  EXPECT_NE(three.state_hash, one.state_hash);
  EXPECT_EQ(config_from_json(to_json(c)).dt_divisor, 3);
  c.dt_divisor = 0;
  EXPECT_THROW(run_sweep_point(c), InputError);
}

TEST(SweepReference, TheKeyGoesStaleWhenAnInputOrTheRecipeChanges) {
  const fs::path dir = temp_dir("sweep_reference_key");
  const fs::path scenario = dir / "capsulorhexis_expert.json";
  std::ofstream(scenario) << R"({"dt_s": 0.008})";
  const ReferenceRecipe recipe = default_reference_recipe("capsulorhexis");
  const std::string key = reference_key(recipe, {scenario});
  EXPECT_EQ(reference_key(recipe, {scenario}), key);
  std::ofstream(scenario) << R"({"dt_s": 0.004})";
  EXPECT_NE(reference_key(recipe, {scenario}), key);
  std::ofstream(scenario) << R"({"dt_s": 0.008})";
  EXPECT_EQ(reference_key(recipe, {scenario}), key);
  ReferenceRecipe finer = recipe;
  finer.dt_divisor *= 2;
  EXPECT_NE(reference_key(finer, {scenario}), key);

  ReferenceFile file;
  file.command = "phaco-perf sweep --reference";
  file.drills["capsulorhexis"] = {.recipe = recipe, .key = key, .metrics = rhexis(5.3, 0.97)};
  // The file survives its JSON.
  const ReferenceFile back = reference_file_from_json(nlohmann::json::parse(to_json(file).dump()));
  ASSERT_EQ(back.drills.count("capsulorhexis"), 1u);
  EXPECT_EQ(back.drills.at("capsulorhexis").key, key);
  EXPECT_EQ(back.drills.at("capsulorhexis").recipe.methods, recipe.methods);

  const SweepRow finest = row_of("capsulorhexis", 8, 1, rhexis(5.0, 0.9));
  const AccuracyReference current = choose_reference("capsulorhexis", &back, key, &finest);
  EXPECT_EQ(current.source, AccuracyReference::Source::Converged);
  EXPECT_DOUBLE_EQ(current.point.metrics["rhexis.diameter_mm"].get<double>(), 5.3);
  const AccuracyReference stale = choose_reference("capsulorhexis", &back, "other", &finest);
  EXPECT_EQ(stale.source, AccuracyReference::Source::FallbackStale);
  EXPECT_NE(stale.label.find("stale"), std::string::npos);
  EXPECT_DOUBLE_EQ(stale.point.metrics["rhexis.diameter_mm"].get<double>(), 5.0);
  const AccuracyReference missing = choose_reference("corneal_incision", &back, "", &finest);
  EXPECT_EQ(missing.source, AccuracyReference::Source::FallbackMissing);
  EXPECT_EQ(choose_reference("capsulorhexis", nullptr, "", nullptr).source,
            AccuracyReference::Source::None);
  // A file that is not a reference is an input error naming the command that remakes it.
  std::ofstream(dir / "bad.json") << R"({"drills": 3})";
  EXPECT_THROW(load_reference_file(dir / "bad.json"), InputError);
  EXPECT_FALSE(load_reference_file(dir / "none.json").has_value());
  fs::remove_all(dir);
}

// Errors are taken against the converged reference, not against the finest default point.
TEST(SweepReference, ErrorsAreMeasuredAgainstTheReference) {
  std::vector<SweepRow> rows = {row_of("capsulorhexis", 3, 1, rhexis(5.0, 0.95)),
                                row_of("capsulorhexis", 8, 1, rhexis(5.5, 0.95)),
                                row_of("capsulorhexis", 3, 1, {{"rhexis.circularity", 0.9}})};
  ReferenceFile file;
  file.drills["capsulorhexis"] = {.recipe = default_reference_recipe("capsulorhexis"),
                                  .key = "k",
                                  .metrics = rhexis(4.0, 0.95)};
  std::map<std::string, AccuracyReference> refs = {
      {"capsulorhexis", choose_reference("capsulorhexis", &file, "k", &rows[1])}};
  measure_accuracy(rows, refs);
  EXPECT_NEAR(rows[0].error_pct, 25.0, 1e-9);  // 5.0 against 4.0, not against level 8's 5.5
  EXPECT_NEAR(rows[1].error_pct, 37.5, 1e-9);  // the finest default point has an error too
  EXPECT_TRUE(std::isnan(rows[2].error_pct));  // no diameter: unknown, never 0
  // Stale: the fallback is the finest default point, and its own error is 0.
  refs["capsulorhexis"] = choose_reference("capsulorhexis", &file, "changed", &rows[1]);
  measure_accuracy(rows, refs);
  EXPECT_NEAR(rows[0].error_pct, 100.0 * 0.5 / 5.5, 1e-9);
  EXPECT_DOUBLE_EQ(rows[1].error_pct, 0.0);
}

TEST(SweepLevels, CgIterationsPerSteppedFrame) {
  SweepPointResult r;
  EXPECT_TRUE(std::isnan(cg_iterations_per_step(r)));
  r.physics["capsule"] = {{"cg_iterations_total", 1000}, {"frames_stepped", 8}};
  EXPECT_DOUBLE_EQ(cg_iterations_per_step(r), 125.0);
  r.physics["capsule"]["cg_iterations_per_step_mean"] = 31.5;  // the solver's own, when reported
  EXPECT_DOUBLE_EQ(cg_iterations_per_step(r), 31.5);
  r.physics["capsule"] = {{"cg_iterations_total", 10}, {"frames_stepped", 0}};
  EXPECT_TRUE(std::isnan(cg_iterations_per_step(r)));
}

TEST(SweepLevels, SpeedUpIsTheOneThreadMeanOverTheTwoThreadMean) {
  SweepRow one = row_of("capsulorhexis", 6, 1, {}), two = row_of("capsulorhexis", 6, 2, {});
  one.r.frame.mean_ms = 9.0;
  two.r.frame.mean_ms = 6.0;
  EXPECT_DOUBLE_EQ(speedup(&one, &two), 1.5);
  EXPECT_TRUE(std::isnan(speedup(&one, nullptr)));
  two.r.frame.mean_ms = 0;
  EXPECT_TRUE(std::isnan(speedup(&one, &two)));
  // Per level, from the rows: the same figure in level_figures.
  two.r.frame.mean_ms = 12.0;
  const auto figs = level_figures({one, two}, "capsulorhexis", 8);
  ASSERT_EQ(figs.size(), 1u);
  EXPECT_EQ(figs[0].level, 6);
  EXPECT_DOUBLE_EQ(figs[0].speedup, 0.75);
}

TEST(SweepLevels, RefreshSlopeIsFittedOverTheChosenLevels) {
  std::vector<SweepRow> rows;
  for (int l = 0; l <= 8; ++l) {
    SweepRow r = row_of("capsulorhexis", l, 1, {});
    r.elements = 100.0 * std::pow(4.0, l);
    // refresh = 0.01·elements^0.5 up to level 6; two outliers above it
    const double ms = l <= 6 ? 0.01 * std::sqrt(r.elements) : 1e4;
    r.r.physics["capsule_cutting"] = {{"physics_refresh_ms_mean", ms}};
    rows.push_back(r);
  }
  const auto figs = level_figures(rows, "capsulorhexis", 8);
  ASSERT_EQ(figs.size(), 9u);
  const PowerFit lo = slope_over_levels(figs, &LevelFigures::refresh_ms_mean, 0, 6);
  ASSERT_TRUE(lo.ok);
  EXPECT_NEAR(lo.slope, 0.5, 1e-9);
  EXPECT_EQ(lo.points, 7u);
  const PowerFit all = slope_over_levels(figs, &LevelFigures::refresh_ms_mean, 0, 8);
  EXPECT_GT(all.slope, 0.6);
  // Levels without the figure (a drill without cuts) give no fit, not a slope of 0.
  EXPECT_FALSE(slope_over_levels(figs, &LevelFigures::cornea_cut_max_ms, 0, 8).ok);
}

// The refresh per cut against what it patched: a finer mesh's tear crosses more springs, so the
// per-cut figure can grow while each patched spring costs the same. The sweep reads the springs
// per refresh from the run report and says both slopes where the per-cut target is missed.
TEST(SweepLevels, RefreshIsAlsoReadPerPatchedSpring) {
  std::vector<SweepRow> rows;
  for (int l = 0; l <= 8; ++l) {
    SweepRow r = row_of("capsulorhexis", l, 1, {});
    r.elements = 1000.0 * std::pow(2.0, l);
    const double springs = 2.0 * std::pow(r.elements, 0.4);  // per refresh
    const double ms_per_spring = 1e-4 * std::pow(r.elements, 0.05);
    r.r.physics["capsule_cutting"] = {{"physics_refresh_ms_mean", ms_per_spring * springs},
                                      {"physics_refresh_ms_max", 1e-3 * springs},
                                      {"physics_refresh_springs_mean", springs}};
    rows.push_back(r);
  }
  // A point of an older run, without the count: no figure per spring, not 0.
  SweepRow old = row_of("capsulorhexis", 9, 1, {});
  old.elements = 1e6;
  old.r.physics["capsule_cutting"] = {{"physics_refresh_ms_mean", 0.5}};
  rows.push_back(old);
  const auto figs = level_figures(rows, "capsulorhexis", 9);
  ASSERT_EQ(figs.size(), 10u);
  EXPECT_NEAR(figs[3].refresh_ms_per_spring, 1e-4 * std::pow(8000.0, 0.05), 1e-12);
  EXPECT_TRUE(std::isnan(figs[9].refresh_ms_per_spring));
  const PowerFit per_cut = slope_over_levels(figs, &LevelFigures::refresh_ms_mean, 0, 8);
  const PowerFit per_spring = slope_over_levels(figs, &LevelFigures::refresh_ms_per_spring, 0, 8);
  ASSERT_TRUE(per_cut.ok && per_spring.ok);
  EXPECT_NEAR(per_cut.slope, 0.45, 1e-9);
  EXPECT_NEAR(per_spring.slope, 0.05, 1e-9);
  // The table gives the refresh in µs and the springs it patched.
  const std::string table = level_tables_md(rows, {"capsulorhexis"}, 8);
  EXPECT_NE(table.find("physics refresh per cut, mean / max (µs) | springs it patched, mean |"),
            std::string::npos)
      << table;
  const double springs0 = 2.0 * std::pow(1000.0, 0.4);  // 31.7 at level 0
  const double us0 = 0.1 * std::pow(1000.0, 0.05) * springs0;
  EXPECT_NE(table.find(fmt("| %.1f / ", us0) + fmt("%.0f | ", springs0) + fmt("%.1f |", springs0)),
            std::string::npos)
      << table;
  // The missed per-cut target is explained by the two slopes.
  const std::string why = why_missed_md(rows, {"capsulorhexis"}, 8, {});
  EXPECT_NE(why.find("grows as elements^0.45"), std::string::npos) << why;
  EXPECT_NE(why.find("The springs a refresh patches grow as elements^0.40"), std::string::npos)
      << why;
  EXPECT_NE(why.find("its cost per patched spring as elements^0.05"), std::string::npos) << why;
}

TEST(SweepLevels, TheParetoReadingSaysWhetherTheDefaultIsOnTheFront) {
  auto pt = [](const std::string& variant, int level, double ms, double err) {
    SweepRow r = row_of("capsulorhexis", level, 1, {}, variant);
    r.r.frame.mean_ms = ms;
    r.error_pct = err;
    return r;
  };
  std::vector<SweepRow> rows = {pt("default", 3, 2.0, 2.0), pt("default", 5, 4.0, 1.0),
                                pt("capsule.integrator=xpbd", 3, 0.5, 0.2)};
  std::string md = pareto_md(rows, "capsulorhexis", "no haptic thread");
  EXPECT_NE(md.find("do not lie on the front"), std::string::npos);
  EXPECT_NE(md.find("xpbd at level 3"), std::string::npos);
  EXPECT_NE(md.find("Both faster and closer at level 3: capsule.integrator=xpbd"),
            std::string::npos);
  rows[2] = pt("capsule.integrator=xpbd", 3, 3.0, 3.0);  // now slower and further off
  md = pareto_md(rows, "capsulorhexis", "no haptic thread");
  EXPECT_NE(md.find("lie on the front.**"), std::string::npos);
  EXPECT_EQ(md.find("do not lie"), std::string::npos);
}

// An integrator on the capsulorhexis front replaces the default only if the membrane study's
// static-load error at the scene's step is within kMechanicsTolerance of implicit Euler's.
TEST(SweepMechanics, AnIntegratorOnTheFrontMustAlsoAnswerALoad) {
  auto pt = [](const std::string& variant, int level, double ms, double err) {
    SweepRow r = row_of("capsulorhexis", level, 1, {}, variant);
    r.r.frame.mean_ms = ms;
    r.error_pct = err;
    r.r.frames = 1200, r.r.sim_s = 10.0;  // 120 steps per second
    return r;
  };
  const std::vector<SweepRow> rows = {pt("default", 3, 2.0, 2.0), pt("default", 5, 4.0, 1.0),
                                      pt("capsule.integrator=semi_implicit_001", 3, 0.5, 1.5),
                                      pt("capsule.integrator=xpbd", 3, 0.6, 1.9)};
  const fs::path dir = temp_dir("sweep_mechanics");
  const auto write = [&dir](double semi_error) {
    nlohmann::json study = nlohmann::json::array();
    const auto add = [&study](const char* method, const char* setting, double error) {
      study.push_back(
          {{"part", "accuracy"}, {"method", method}, {"setting", setting}, {"error", error}});
    };
    add("implicit_euler", "dt 1/120 s", 0.05);
    add("implicit_euler", "dt 1/480 s", 0.001);  // another step: not the scene's
    add("semi_implicit_001", "dt 1/120 s", semi_error);
    add("xpbd 8 it", "dt 1/120 s", 45.0);
    std::ofstream(dir / "membrane.json") << study.dump();
  };
  write(1.0);
  const auto errors = membrane_static_errors(dir / "membrane.json", "dt 1/120 s");
  ASSERT_EQ(errors.count("implicit_euler"), 1u);
  EXPECT_DOUBLE_EQ(errors.at("implicit_euler").error, 0.05);
  EXPECT_EQ(errors.at("xpbd").method, "xpbd 8 it");
  std::string md = integrator_mechanics_md(rows, dir / "membrane.json", "no haptic thread");
  EXPECT_NE(md.find("(dt 1/120 s)"), std::string::npos) << md;
  EXPECT_NE(md.find("semi_implicit_001: 100.0 %, so the default stays"), std::string::npos) << md;
  EXPECT_NE(md.find("xpbd: 4500.0 % (xpbd 8 it), so the default stays"), std::string::npos) << md;
  EXPECT_EQ(md.find("may replace"), std::string::npos) << md;
  write(0.08);  // within 2x of implicit Euler's 0.05
  md = integrator_mechanics_md(rows, dir / "membrane.json", "no haptic thread");
  EXPECT_NE(md.find("semi_implicit_001: 8.0 %: **it may replace the default.**"), std::string::npos)
      << md;
  // Without the study's file nothing is judged, and says so.
  fs::remove(dir / "membrane.json");
  md = integrator_mechanics_md(rows, dir / "membrane.json", "no haptic thread");
  EXPECT_NE(md.find("no integrator on the front is judged"), std::string::npos) << md;
  // With the default on the front there is nothing to say.
  EXPECT_EQ(integrator_mechanics_md({pt("default", 3, 2.0, 2.0), pt("default", 5, 4.0, 1.0)},
                                    dir / "membrane.json", "no haptic thread"),
            "");
  fs::remove_all(dir);
}

// "Why a target is missed" is made of the points' figures: the system with the slowest frame and
// the refresh's share of the worst frame; nothing when the targets are met.
TEST(SweepLevels, WhyMissedIsMadeOfTheFigures) {
  SweepRow r = row_of("capsulorhexis", 3, 2, {});
  r.r.frame = {"frame", 1.0, 10.0, 20.0, 2.0};
  r.r.systems = {{"capsule_dynamics", 0.9, 4.0, 5.0, 1.0}, {"capsule_cut", 0.0, 0.1, 18.0, 0.1}};
  r.r.physics["capsule_cutting"] = {{"physics_refresh_ms_max", 17.0}, {"edit_ms_max", 0.2}};
  std::string md = why_missed_md({r}, {"capsulorhexis"}, 3, {});
  EXPECT_NE(md.find("slowest single frame is capsule_cut (18.0 ms, 90 % of the worst frame)"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("up to 17.0 ms (85 % of the worst frame)"), std::string::npos) << md;
  r.r.frame = {"frame", 1.0, 3.0, 6.0, 2.0};  // within 4 ms p99 and 8 ms max
  md = why_missed_md({r}, {"capsulorhexis"}, 3, {});
  EXPECT_EQ(md.find("slowest single frame"), std::string::npos) << md;
  EXPECT_NE(md.find("is met"), std::string::npos) << md;
}

}  // namespace
}  // namespace phaco::perf
