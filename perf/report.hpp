#pragma once
// Where a study's figures go: perf/results/<study>.csv and .json (one table of rows), charts
// perf/results/<study>_*.png, and a markdown section perf/results/<study>.md. RESULTS.md is then
// assembled from the machine description and every section present, in a fixed order, so running
// one study regenerates the file without losing the others' sections.
#include <filesystem>
#include <string>
#include <variant>
#include <vector>

namespace phaco::perf {

// A flat table: named columns, rows of numbers or strings. Written as CSV and as a JSON array of
// objects (non-finite numbers become null in JSON and empty in CSV).
struct Table {
  using Cell = std::variant<double, std::string>;
  std::vector<std::string> columns;
  std::vector<std::vector<Cell>> rows;

  void add(std::vector<Cell> row);  // throws std::invalid_argument when the width is wrong
};

void write_csv(const Table& table, const std::filesystem::path& file);
void write_json(const Table& table, const std::filesystem::path& file);

// Studies in the order RESULTS.md shows them; a section file of another name comes after these,
// alphabetically.
const std::vector<std::string>& study_order();

// results_dir / (study + ".md").
void write_section(const std::filesystem::path& results_dir, const std::string& study,
                   const std::string& markdown);

// The whole RESULTS.md text: header, machine table, then every section present in results_dir.
std::string assemble_results(const std::filesystem::path& results_dir,
                             const std::string& machine_markdown);

// Progress bar on stderr: "[#####.....] 12/40 what".
class Progress {
 public:
  explicit Progress(int total) : total_(total) {}
  void step(const std::string& what);  // announces the next item; counts the previous one done
  void finish();
  int total() const { return total_; }

 private:
  int total_ = 0, done_ = -1;
};

// "load average 1.23 (1 min) when measured" from /proc/loadavg: a figure measured while other
// work shares the cores is slower than the machine can do, and says so.
std::string load_note();

// printf-style formatting of one number.
std::string fmt(const char* format, double v);
// The same, or "-" for a NaN or infinite value (a figure that was not measured).
std::string fmt_or_dash(const char* format, double v);

// The mean of repeated measurements and its two-sided 95 % interval (Student's t, n − 1 degrees of
// freedom): how studies report a figure that differs from run to run on a shared machine. With one
// value the interval is unbounded (±inf); with none, everything is NaN.
struct MeanInterval {
  double mean = 0, lo = 0, hi = 0;
};
MeanInterval mean_interval95(const std::vector<double>& values);

}  // namespace phaco::perf
