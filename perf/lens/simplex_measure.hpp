#pragma once
// Measurements of the simplex cells (systems/simplex) for the `phaco-perf lens` study, one row per
// lens level: construction, the removal primitive per simplex (mean and p99), the boundary
// rebuilt from scratch, the surfaces, and fragment labelling (painting against the parallel
// union-find on 1 and 2 threads). Returns rows only; the harness prints and charts them.
//
// Two removal workloads: a crater (cells in order of distance from the anterior pole, as a tip
// sculpting in: mostly surface cells, the seed's three cases) and scattered (random cells: mostly
// interior cavities, every edge walk runs round a closed fan). Fragment labelling is timed on the
// whole lens (one fragment) and after half of the cells were removed at random (many fragments).
#include <cstdint>
#include <vector>

namespace phaco::perf {

struct SimplexMeasureOptions {
  std::vector<int> levels = {0, 1, 2, 3};
  uint32_t removals = 2000;  // timed removals per workload (at most a quarter of the cells)
  double min_seconds = 0.1;  // per timing repeat of the whole-structure passes
  int repeats = 3;
  uint32_t seed = 1;
  uint32_t union_find_grain = 4096;
};

struct SimplexRow {
  int level = 0;
  uint32_t cells = 0;
  uint32_t external_faces = 0;
  double build_ms = 0.0;                                   // build_cells: the seed's three loops
  double crater_mean_us = 0.0, crater_p99_us = 0.0;        // remove_cell, crater order
  double scattered_mean_us = 0.0, scattered_p99_us = 0.0;  // remove_cell, random order
  double rebuild_links_ms = 0.0;  // rebuild_boundary_links from the neighbours (loop 3 alone)
  double check_ms = 0.0;          // check_boundary: neighbours and links rebuilt and compared
  double surface_ms = 0.0;        // build_boundary_surface (the dual surface by the links)
  double extract_ms = 0.0;        // extract_external_faces
  double paint_ms = 0.0;          // whole lens, one fragment
  double union_find_1t_ms = 0.0, union_find_2t_ms = 0.0;
  uint32_t shattered_fragments = 0;  // after half the cells removed at random
  double shattered_paint_ms = 0.0;
  double shattered_union_find_1t_ms = 0.0, shattered_union_find_2t_ms = 0.0;
  double update_mean_us = 0.0;  // confirm_split + update_fragments after one crater removal
  double update_relabel_fraction = 0.0;  // share of those removals that still relabelled
};

std::vector<SimplexRow> measure_simplex(const SimplexMeasureOptions& options);

}  // namespace phaco::perf
