// phaco-perf bandwidth: this machine's memory bandwidth, the ceiling a memory-bound pass such as
// the spring force pass is compared with (perf/bandwidth.hpp).
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "engine/core/error.hpp"
#include "perf/bandwidth.hpp"
#include "perf/report.hpp"
#include "perf/studies.hpp"

namespace phaco::perf {

namespace {

constexpr size_t kMiB = 1024 * 1024;

// Array size for the DRAM figure: twice the last-level cache per array (three arrays: six times
// the cache in all), at least 256 MiB; quick runs use 256 MiB.
size_t dram_array_bytes(bool quick) {
  if (quick) return 256 * kMiB;
  return std::max<size_t>(256 * kMiB, 2 * last_level_cache_bytes());
}

}  // namespace

void run_bandwidth(const StudyOptions& options) {
  if (!options.extra.empty())
    throw InputError("bandwidth: unknown option '" + options.extra[0] + "'");
  const std::string load = load_note();
  const size_t llc = last_level_cache_bytes();
  const size_t big = dram_array_bytes(options.quick);
  const size_t small = 4 * kMiB;  // three arrays of 4 MiB: inside the last-level cache, beyond L2
  struct Case {
    const char* where;
    size_t bytes;
  };
  const std::vector<Case> cases = {{"memory", big}, {"cache", small}};
  Progress progress(static_cast<int>(cases.size() * 4));
  Table t;
  t.columns = {"where", "kernel", "threads", "array_mib", "gb_per_s"};
  std::vector<Bandwidth> results;
  for (const Case& c : cases) {
    for (const char* kernel : {"copy", "triad"}) {
      for (int threads : {1, 2}) {
        progress.step(std::string("bandwidth: ") + c.where + " " + kernel + " " +
                      std::to_string(threads) + "T");
        const int passes = c.bytes > 64 * kMiB ? (options.quick ? 3 : 5) : 200;
        const Bandwidth b = measure_bandwidth(kernel, c.bytes, threads, passes);
        t.add({std::string(c.where), std::string(kernel), double(threads),
               double(b.array_bytes) / kMiB, b.gb_per_s});
      }
    }
  }
  progress.finish();
  const auto dir = options.out_dir / "results";
  write_csv(t, dir / "bandwidth.csv");
  write_json(t, dir / "bandwidth.json");

  std::string md = "## Memory bandwidth\n\n";
  md += std::string("Measured by `phaco-perf bandwidth") + (options.quick ? " --quick" : "") +
        "`, " + load + ". ";
  md +=
      "STREAM-style kernels over double arrays (copy c = a: 16 bytes per element; triad a = b + "
      "s·c: 24 bytes; "
      "write-allocate traffic not counted, as STREAM does), best of several passes, oneTBB static "
      "partition. "
      "Last-level cache reported by the OS: " +
      fmt("%.0f", double(llc) / kMiB) + " MiB";
  md += big >= 2 * llc ? " — the memory arrays are twice that each, six times it in all.\n\n"
                       : " — **quick run: the memory arrays are not much larger than that cache, "
                         "so the 'memory' "
                         "figure is partly a cache figure.**\n\n";
  md += "| where | kernel | threads | array (MiB) | GB/s |\n|---|---|---:|---:|---:|\n";
  for (const auto& row : t.rows) {
    md += "| " + std::get<std::string>(row[0]) + " | " + std::get<std::string>(row[1]) + " | " +
          fmt("%.0f", std::get<double>(row[2])) + " | " + fmt("%.0f", std::get<double>(row[3])) +
          " | " + fmt("%.1f", std::get<double>(row[4])) + " |\n";
  }
  write_section(dir, "bandwidth", md);
}

}  // namespace phaco::perf
