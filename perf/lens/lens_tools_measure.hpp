#pragma once
// Cost of the lens tools per frame (issue 5 item 4): phaco erosion (roulette in the cone),
// aspirator, hook, gravity + viscosity Euler step and environment constraints, on n cells spread
// uniformly through the standard lens (DESIGN.md §6), 1 or more threads. Plain rows; the
// `phaco-perf lens` study prints and charts them.
#include <cstdint>
#include <span>
#include <vector>

namespace phaco::perf {

struct LensToolsRow {
  uint32_t cells = 0;
  int threads = 1;
  uint32_t frames = 0;      // frames timed
  double ms_per_frame = 0;  // the five passes together
  double erosion_ms = 0, aspirate_ms = 0, hook_ms = 0, integrate_ms = 0, constrain_ms = 0;
  double removed_per_frame = 0;  // cells the roulette removed, mean over the timed frames
};

// For every (cells, threads) pair: `frames` frames of 1/120 s (after `warmup` untimed ones) of the
// standard tool set — phaco tip (pedal 3, power 0.6) advancing into the lens, aspirating at 300
// mmHg through its own port (as a phaco handpiece does), hook sweeping sideways — on a fresh lens
// each time; viscosity on, gravity off (shape matching, not part of this measure, holds the lens
// up). Times are means per frame of the best of `repeats` runs.
std::vector<LensToolsRow> measure_lens_tools(std::span<const uint32_t> cell_counts,
                                             std::span<const int> threads, uint32_t frames = 120,
                                             uint32_t warmup = 10, int repeats = 3);

}  // namespace phaco::perf
