#pragma once
// This machine's memory bandwidth, STREAM-style (McCalpin): copy c = a and triad a = b + s·c over
// double arrays, best of several passes, at 1..N threads. Bytes counted as STREAM does (16 per
// element for copy, 24 for triad; the write-allocate read is not counted). Arrays much larger than
// the last-level cache give the DRAM figure; small ones give the cache figure the spring pass of a
// mid-size mesh actually sees.
#include <cstddef>
#include <string>

namespace phaco::perf {

// Size of the largest cache of CPU 0 from /sys/devices/system/cpu/cpu0/cache (0 if unknown).
size_t last_level_cache_bytes();

struct Bandwidth {
  std::string kernel;  // "copy" or "triad"
  int threads = 1;
  size_t array_bytes = 0;  // per array
  double gb_per_s = 0;     // 1e9 bytes per second, best pass
};

// Runs `passes` passes of the kernel on arrays of `array_bytes` each inside a oneTBB arena of
// `threads` threads (static partition, arrays first-touched by the same partition).
Bandwidth measure_bandwidth(const std::string& kernel, size_t array_bytes, int threads, int passes);

}  // namespace phaco::perf
