#pragma once
// The sweep's accuracy and its checks (issue 9, issue 17 item 3): each point's error against its
// drill's converged reference, and what a run must hold for CI (a --quick run enforces it; so does
// every full run): every point runs to its end, 1 and 2 threads give the same state hash, the
// default methods never diverge and stay within their accuracy bounds.
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "perf/sweep/sweep_data.hpp"
#include "perf/sweep/sweep_reference.hpp"

namespace phaco::perf {

// Accuracy bounds the default methods must keep from level `from` up (checked in CI by --quick):
// the error of the drill's scored outcome against the reference level, percent.
struct Bound {
  int from_level;
  double max_error_pct;
};
Bound bound_of(const std::string& drill);

// A committed results file: the out dir's, else the source tree's perf/results (a sweep into
// another --out-dir, e.g. CI's quick run, still measures against the committed reference).
std::filesystem::path results_file(const std::filesystem::path& dir, const char* name);

struct SweepAccuracy {
  std::map<std::string, AccuracyReference> references;  // what each drill's error_pct is against
  std::map<std::string, const SweepRow*> finest;  // the default methods' finest point per drill
  std::vector<SweepRow> baseline;  // the default before issue 17, against the same references
  std::string baseline_source;
};

// Sets every row's error against its drill's reference: the converged one of
// sweep_reference.json when its key matches today's inputs, else (labelled) the default methods
// at the finest level. The baseline's errors are taken against the same references.
SweepAccuracy assess_accuracy(std::vector<SweepRow>& rows, const std::vector<std::string>& drills,
                              const std::filesystem::path& dir, int finest_level);

// Appends to `failures` what the points break of the checks above; the accuracy bounds are judged
// against the run's own finest level (reference_level): convergence.
void check_points(const std::vector<SweepRow>& rows, const SweepAccuracy& accuracy,
                  const std::vector<std::string>& drills, int reference_level,
                  std::vector<std::string>& failures);

}  // namespace phaco::perf
