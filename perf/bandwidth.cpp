#include "perf/bandwidth.hpp"

#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/partitioner.h>
#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>

#include "engine/core/clock.hpp"

namespace phaco::perf {

size_t last_level_cache_bytes() {
  size_t best = 0;
  const std::filesystem::path dir = "/sys/devices/system/cpu/cpu0/cache";
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    std::ifstream in(entry.path() / "size");
    std::string s;
    if (!(in >> s) || s.empty()) continue;
    size_t mult = 1;
    if (s.back() == 'K')
      mult = 1024, s.pop_back();
    else if (s.back() == 'M')
      mult = 1024 * 1024, s.pop_back();
    try {
      best = std::max(best, static_cast<size_t>(std::stoull(s)) * mult);
    } catch (const std::exception&) {
    }
  }
  return best;
}

Bandwidth measure_bandwidth(const std::string& kernel, size_t array_bytes, int threads,
                            int passes) {
  const bool triad = kernel == "triad";
  if (!triad && kernel != "copy")
    throw std::invalid_argument("bandwidth kernel must be copy or triad");
  const size_t n = std::max<size_t>(array_bytes / sizeof(double), 1024);
  // Uninitialised storage, so the first touch happens in the parallel loop below.
  std::unique_ptr<double[]> a(new double[n]), b(new double[n]), c(new double[n]);
  double* pa = a.get();
  double* pb = b.get();
  double* pc = c.get();
  tbb::task_arena arena(threads);
  const auto run = [&](auto&& body) {
    arena.execute([&] {
      tbb::parallel_for(
          tbb::blocked_range<size_t>(0, n, 1 << 16),
          [&](const tbb::blocked_range<size_t>& r) { body(r.begin(), r.end()); },
          tbb::static_partitioner());
    });
  };
  run([&](size_t lo, size_t hi) {
    for (size_t i = lo; i < hi; ++i) pa[i] = 1.0, pb[i] = 2.0, pc[i] = 0.5;
  });
  const double scalar = 3.0;
  double best_s = 1e30;
  for (int p = 0; p < std::max(passes, 1) + 1; ++p) {  // pass 0 warms up
    Stopwatch clock;
    if (triad) {
      run([&](size_t lo, size_t hi) {
        for (size_t i = lo; i < hi; ++i) pa[i] = pb[i] + scalar * pc[i];
      });
    } else {
      run([&](size_t lo, size_t hi) {
        for (size_t i = lo; i < hi; ++i) pc[i] = pa[i];
      });
    }
    const double s = clock.elapsed_s();
    if (p > 0) best_s = std::min(best_s, s);
  }
  // Keep the result observable so the passes are not optimised away.
  volatile double sink = pa[n / 2] + pc[n / 3];
  (void)sink;
  Bandwidth out;
  out.kernel = kernel;
  out.threads = threads;
  out.array_bytes = n * sizeof(double);
  out.gb_per_s = static_cast<double>(n) * (triad ? 24.0 : 16.0) / best_s * 1e-9;
  return out;
}

}  // namespace phaco::perf
