#pragma once
// Cost of the fragmenting lens per frame (issue 5 target: shape matching + SPH for 50k cells
// ≤ 3 ms per frame on 2 threads): the lens of a level cut by slabs into pieces, then stepped with
// no tool (gravity, viscosity, fragment contact, constraints, shape matching). Plain rows.
#include <cstdint>
#include <span>
#include <vector>

namespace phaco::perf {

struct FragmentLensRow {
  int level = 0;
  uint32_t cells = 0;  // alive after the cuts
  uint32_t fragments = 0;
  int threads = 1;
  uint32_t frames = 0;
  double ms_per_frame = 0;   // best of the repeats, mean over the frames
  double contact_pairs = 0;  // inter-fragment pairs per frame, mean
  double contact_particles = 0;
};

// `cuts` slab planes per axis in x and y (0 = the whole lens, one fragment; 1 = four pieces...).
std::vector<FragmentLensRow> measure_fragment_lens(std::span<const int> levels,
                                                   std::span<const int> cuts,
                                                   std::span<const int> threads,
                                                   uint32_t frames = 60, int repeats = 3);

}  // namespace phaco::perf
