#pragma once
// The converged reference the sweep measures accuracy against (issue 17 item 3), made by
// `phaco-perf sweep --reference` and kept in perf/results/sweep_reference.json.
//
// Before it, a point's error was taken against the default methods' own answer at the finest level,
// so the default could never look wrong. The reference is a run off the default path:
//  - capsulorhexis: the whole capsule's dynamics (capsule.active_set=off), a smaller time step
//    (the scenario's dt_s / dt_divisor, the same tracks) and a tighter CG tolerance
//    (capsule.cg_tolerance), at the finest level the budget affords;
//  - sculpting and incision: the finest level at a smaller time step (the tools' paths sampled
//    dt_divisor times more densely). Their scenes have no dynamics, so there is no active set or
//    tolerance to change; the error they show is the mesh's and the sampling's.
//
// A reference depends on its recipe and on the files the run reads (the drill's expert scenario,
// the eye's parameters, the drill's targets): their hash is its key. When a file changes, the
// reference is stale, and the sweep falls back, saying so, to the default methods at its finest
// level.
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "perf/sweep/sweep_data.hpp"

namespace phaco::perf {

// How a drill's reference run is made.
struct ReferenceRecipe {
  std::string drill;
  int level = 8;
  int dt_divisor = 1;                          // dt = the scenario's dt_s / dt_divisor
  std::map<std::string, std::string> methods;  // added to the scenario's `methods`
};

// The recipe `--reference` uses unless told otherwise (docs/perf_sweep.md says why).
ReferenceRecipe default_reference_recipe(const std::string& drill);

// "level 3, whole capsule (capsule.active_set=off), dt/4, CG tolerance 1e-09"
std::string describe(const ReferenceRecipe& recipe);

// The point a recipe runs: 1 thread, no haptic thread (nothing is timed).
SweepPointConfig reference_config(const ReferenceRecipe& recipe,
                                  const std::filesystem::path& scenario,
                                  const std::filesystem::path& cache_dir);

// FNV-1a (64-bit, hex) over the recipe and the bytes of each input file: what the reference
// depends on. A missing file hashes as its name alone.
std::string reference_key(const ReferenceRecipe& recipe,
                          const std::vector<std::filesystem::path>& inputs);

// The input files of a drill's reference: data/scenarios/<drill>_expert.json,
// data/eye/standard_eye.json, data/drills/<drill>.json.
std::vector<std::filesystem::path> reference_inputs(const std::filesystem::path& data_dir,
                                                    const std::string& drill);

struct DrillReference {
  ReferenceRecipe recipe;
  std::string key;                                    // reference_key when it was made
  nlohmann::json metrics = nlohmann::json::object();  // the drill's accuracy metrics
  std::string state_hash;
  uint64_t frames = 0;
  double wall_s = 0;
  double cg_iterations_per_step = 0;  // capsulorhexis: the reference's own solve, for the record
  std::string load;                   // the machine's load when it was made (load_note)
};

struct ReferenceFile {
  std::string command, load, made_at;
  std::map<std::string, DrillReference> drills;
};

nlohmann::json to_json(const ReferenceFile& f);
ReferenceFile reference_file_from_json(const nlohmann::json& j);  // throws nlohmann's on bad input

// Reads the file; nullopt when it does not exist. Throws InputError when it exists but is
// unreadable.
std::optional<ReferenceFile> load_reference_file(const std::filesystem::path& path);

// What a drill's errors are measured against.
struct AccuracyReference {
  enum class Source { Converged, FallbackMissing, FallbackStale, None };
  Source source = Source::None;
  SweepPointResult point;  // config.drill and metrics: what accuracy_error_pct compares with
  std::string label;       // for the report, e.g. "the converged reference (level 3, ...)"
};

// The file's reference when it has the drill and its key equals current_key; otherwise the
// default methods' finest point (fallback, labelled missing or stale); None without either.
AccuracyReference choose_reference(const std::string& drill, const ReferenceFile* file,
                                   const std::string& current_key, const SweepRow* finest_default);

// Sets every row's error_pct and error_detail against its drill's reference (NaN without one).
void measure_accuracy(std::vector<SweepRow>& rows,
                      const std::map<std::string, AccuracyReference>& references);

struct ReferenceRunOptions {
  std::vector<std::string> drills;
  int level = -1;      // ≥ 0: every drill's recipe at this level instead of its default
  int dt_divisor = 0;  // ≥ 1: instead of the recipe's
  std::filesystem::path results_dir;  // sweep_reference.json is written here
  std::filesystem::path data_dir;     // data/ (scenarios, eye, drills)
  std::filesystem::path cache_dir;    // mesh cache
  std::filesystem::path exe;          // phaco-perf, for the point processes
};

// `phaco-perf sweep --reference`: runs each drill's recipe in a process of its own and writes
// results_dir/sweep_reference.json, keeping the drills it did not run from the existing file.
// Throws CheckFailed-like std::runtime_error when a reference run fails (the file keeps the
// others).
void make_sweep_reference(const ReferenceRunOptions& options);

}  // namespace phaco::perf
