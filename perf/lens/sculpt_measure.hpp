#pragma once
// Measurements of tetrahedral sculpting (systems/sculpt) for `phaco-perf lens`: per level ×
// broadphase × narrowphase, the step time along a standard trench sweep and the removed volume
// against the exact swept volume. Returns rows; prints and writes nothing.
#include <cstdint>
#include <string>
#include <vector>

#include "engine/core/math.hpp"
#include "systems/sculpt/sculpt.hpp"

namespace phaco::perf {

struct SculptMeasureOptions {
  std::vector<int> levels = {0, 1, 2, 3};
  std::vector<sculpt::Broadphase> broadphases = {sculpt::Broadphase::Octree,
                                                 sculpt::Broadphase::Dbvt};
  std::vector<sculpt::Narrowphase> narrowphases = {sculpt::Narrowphase::CentreInSphere,
                                                   sculpt::Narrowphase::ExactGjk,
                                                   sculpt::Narrowphase::ExactMpr};
  double radius_mm = 0.45;  // full power (sculpt_radius_mm(3, 1))
  double step_mm = 0.04;    // tip travel per step (≈ 5 mm/s at 120 Hz)
  double reference_column_mm = 0.01;
  bool use_mesh_cache = true;  // eye::MeshCache (TetGen at level 7 takes seconds)
};

struct SculptMeasureRow {
  int level = 0;
  std::string broadphase, narrowphase;
  uint32_t tets = 0;
  uint32_t steps = 0;
  double build_ms = 0;  // topology + broadphase structure
  double step_p50_us = 0, step_p99_us = 0, step_max_us = 0;
  double broadphase_steps = 0;  // fraction of steps that ran the broadphase
  double mean_work = 0;         // SculptStats::work() per step
  uint32_t removed_tets = 0;
  double removed_mm3 = 0;
  double reference_mm3 = 0, reference_error_mm3 = 0;  // swept_volume_in_lens and its estimate
  double relative_error = 0;                          // removed / reference - 1
};

// The standard sweep: enter above the lens, three trench strokes along x at falling depth, leave.
std::vector<Vec3> standard_sculpt_path();

std::vector<SculptMeasureRow> measure_sculpt(const SculptMeasureOptions& options);

}  // namespace phaco::perf
