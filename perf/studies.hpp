#pragma once
// The studies phaco-perf runs. Each measures, writes perf/results/<study>.csv/.json, its charts
// perf/results/<study>_*.png and its markdown section perf/results/<study>.md, then RESULTS.md is
// reassembled from every section present (perf/report.hpp).
#include <charconv>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "engine/core/error.hpp"

namespace phaco::perf {

// A study option's whole-number value: "sweep: --max-level expects a whole number, got 'x'" as an
// input error (never std::stoi's bare "stoi"). Range checks stay with each option.
inline int option_int(const std::string& study, const std::string& option,
                      const std::string& text) {
  int v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc{} || end != text.data() + text.size())
    throw InputError(study + ": " + option + " expects a whole number, got '" + text + "'");
  return v;
}

struct StudyOptions {
  bool quick = false;              // small levels, few steps: about a minute, for CI
  std::filesystem::path out_dir;   // holds RESULTS.md and results/
  std::vector<std::string> extra;  // study-specific options left after the common ones
};

void run_foundation(const StudyOptions& options);
void run_bandwidth(const StudyOptions& options);
void run_membrane(const StudyOptions& options);
void run_cut(const StudyOptions& options);
void run_lens(const StudyOptions& options);
void run_haptics(const StudyOptions& options);
void run_drills(const StudyOptions& options);
void run_tear(const StudyOptions& options);
void run_trainer_study(const StudyOptions& options);
void run_trainer_ab(const StudyOptions& options);
void run_sweep(const StudyOptions& options);
void run_soak(const StudyOptions& options);
void run_records(const StudyOptions& options);
void run_nucleus(const StudyOptions& options);
void run_cohorts(const StudyOptions& options);

// A study's own checks failed (e.g. the sweep's accuracy bounds): the figures are still written,
// and phaco-perf exits 1 naming what failed.
struct CheckFailed : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Rewrites out_dir/RESULTS.md from the machine description and the sections in out_dir/results.
void regenerate_results(const std::filesystem::path& out_dir);

}  // namespace phaco::perf
