#pragma once
// A run compared with an expert's run (issue 7 item 4, docs/compare.md): time-aligned
// differences in path, speed and force per hand, and metric-by-metric differences.
//
// Reads two run reports (the JSON `phaco run --report` writes: "drill", "series" with t_s and per
// hand pos_mm / speed_mm_s / force_mN, decimated to ≤ 2000 samples; "metrics") and writes nothing.
//
// Alignment: dynamic time warping (DTW) of the tool-tip paths, per hand, with the symmetric
// recurrence D(i,j) = d(i,j) + min(D(i−1,j), D(i,j−1), D(i−1,j−1)), d = |p_run(i) − p_expert(j)|
// in mm, restricted to the adjustment window of Sakoe & Chiba (1978), "Dynamic programming
// algorithm optimization for spoken word recognition", IEEE Trans. ASSP 26(1):43–49, §II: here
// |j − i·(m−1)/(n−1)| ≤ w around the diagonal scaled to the two lengths, so the work and memory
// are O(n·w), not O(n·m). After alignment every run sample i has the expert samples the warping
// path pairs with it; its differences are the averages over them. So the aligned series are on the
// run's own time axis, one value per run sample.
//
// Also given, for contrast: the plain time ratio (run duration / expert duration) and the same
// differences taken at equal times without warping (the expert's series interpolated at the run's
// t, held at its last value after it ends).
#include <cstddef>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace phaco::compare {

struct CompareOptions {
  // Sakoe–Chiba window half-width as a fraction of the longer series (their r); never narrower
  // than the slope of the scaled diagonal needs to keep the band connected.
  double band_fraction = 0.1;
};

// Statistics of one difference series (run − expert, or a distance).
struct DifferenceStats {
  double mean = 0;  // signed mean (a distance: its mean)
  double rms = 0;
  double max = 0;  // largest magnitude
};

struct HandComparison {
  std::string hand;  // "left" / "right"
  std::size_t run_samples = 0, expert_samples = 0;
  std::size_t band = 0;  // the window half-width w used, in samples
  // After DTW alignment.
  DifferenceStats path_distance_mm;  // |p_run − p_expert|
  DifferenceStats speed_diff_mm_s;   // speed_run − speed_expert
  DifferenceStats force_diff_mN;     // force_run − force_expert
  // At equal times, without warping (for contrast).
  DifferenceStats plain_path_distance_mm, plain_speed_diff_mm_s, plain_force_diff_mN;
  // The aligned series, one entry per run sample: the run's time, the expert's matched time
  // (mean over the matched samples), and the differences above.
  std::vector<double> t_s, expert_t_s, distance_mm, speed_diff_mm_s_series, force_diff_mN_series;
};

struct MetricDifference {
  std::string name;
  double run = 0, expert = 0;
  double difference = 0;  // run − expert
};

struct Comparison {
  std::string run_file, expert_file, drill;
  double run_time_s = 0, expert_time_s = 0;  // the last sample's time in each series
  double time_ratio = 0;                     // run_time_s / expert_time_s (0 when expert is 0)
  std::vector<HandComparison> hands;         // left first
  std::vector<MetricDifference> metrics;     // every numeric metric both reports have, by name
};

// Compares two parsed run reports; `run_name` / `expert_name` name them in messages. Throws
// InputError naming the file and the JSON field for a malformed report (not an object, no
// "series", a series field missing or not numbers, lengths that disagree), reports of different
// drills ("drill"), or a hand one report has and the other has not ("series.hands.left").
Comparison compare_reports(const nlohmann::json& run, const nlohmann::json& expert,
                           const std::string& run_name, const std::string& expert_name,
                           const CompareOptions& options = {});

// Reads both files (InputError naming the file when one cannot be read or is not JSON).
nlohmann::json read_report(const std::filesystem::path& file);
Comparison compare_files(const std::filesystem::path& run, const std::filesystem::path& expert,
                         const CompareOptions& options = {});

// Banded DTW of two 3-D paths (x, y, z per sample, flattened): the warping path as (i, j) pairs
// from (0, 0) to (n−1, m−1). Exposed for tests. Throws std::invalid_argument on an empty path.
std::vector<std::pair<std::size_t, std::size_t>> dtw_path(const std::vector<double>& a,
                                                          const std::vector<double>& b,
                                                          std::size_t band);

nlohmann::json to_json(const Comparison& c);
// A short table: per hand the aligned and plain figures, then the metric differences.
std::string summary_text(const Comparison& c);

}  // namespace phaco::compare
