#pragma once
// How closely a cut follows the tool (issue 4: "the cut edge stays within the snap threshold of the
// tool path"): the Hausdorff distance between the cut's lips — the membrane's free edges except
// those joining two anchored particles (the held rim) — and the tool's path as a polyline. Both
// sides are sampled: the lips at their ends and midpoints, the tool path every sample_mm.
//
// Reads: particles, triangles, adjacency (through the cut mesh). Writes nothing.
#include <span>

#include "systems/cut/membrane_edit.hpp"

namespace phaco::rhexis {

struct CutFidelity {
  double cut_to_tool_mm = 0.0;  // furthest lip point from the tool path
  double tool_to_cut_mm = 0.0;  // furthest tool-path point from the lips
  double hausdorff_mm = 0.0;    // the larger of the two
  size_t lip_edges = 0;
};

// A path of fewer than two points, or a mesh without lips, gives lip_edges = 0 and zeros.
CutFidelity measure_cut_fidelity(const cut::CutMesh& mesh, std::span<const Vec3> tool_path,
                                 double sample_mm = 0.01);

}  // namespace phaco::rhexis
