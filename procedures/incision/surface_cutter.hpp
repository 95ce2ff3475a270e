#pragma once
// One corneal surface cut by the keratome (seed 000 §5.2 progressive cutting), shared by the
// scripted incision (procedures/incision/scripted_incision) and the running scene
// (procedures/scene/cornea_cutting). Per surface two cut paths grow from the puncture, one to each
// end of the blade's section with that surface (incision::BladeSection):
//
//        left end  <-------- puncture --------> right end      (one surface, seen along n)
//
// An end is fed only while it moves away from the puncture (the cut widens; it never heals), so the
// sides of a fully inserted blade and its withdrawal cut nothing more. The right path starts at the
// vertex the left path's first cut made of the puncture, so the two paths are one cut.
//
// Reads and writes: the cut mesh (particles, triangles, springs, topology) through cut::CutMesh.
#include <cstdint>
#include <vector>

#include "systems/cut/progressive_cut.hpp"
#include "systems/incision/section.hpp"

namespace phaco::corneal_incision {

// One cut path from a surface's puncture toward one side's ends.
struct SidePath {
  cut::CutPath path;
  double reach_mm = 0.0;  // distance from the puncture of the last end fed
};

// The two paths of one surface (0 = left, 1 = right), growing from its puncture.
struct SurfaceCutter {
  bool started = false;
  Vec3 puncture = Vec3::Zero();
  // Where the puncture's search starts (e.g. cut::nearest_binned_triangle); kInvalidIndex: a scan
  // of every triangle finds it.
  uint32_t start_triangle = kInvalidIndex;
  SidePath side[2];
  uint32_t tips[2] = {kInvalidIndex, kInvalidIndex};  // crack tips, kept when the paths end
};

// One frame on one surface: start both paths at the puncture once the tip is through, then feed
// this frame's section ends. True if the mesh changed; `segments` counts the segments that did.
bool cut_surface(cut::CutMesh& m, SurfaceCutter& s, const incision::BladeSection& section,
                 const cut::CutSettings& settings, cut::EditLog& log, uint64_t& segments);

// The blade has stopped: each waiting end gets its last sample again at `min_angle_deg`
// (cut::finish_cut). True if the mesh changed.
bool finish_surface(cut::CutMesh& m, SurfaceCutter& s, const cut::CutSettings& settings,
                    double min_angle_deg, cut::EditLog& log, uint64_t& segments);

// The path's crack tip if it is a live particle, else kInvalidIndex.
uint32_t live_tip(const cut::CutMesh& m, const cut::CutPath& p);

// The tool polyline of one surface: the left ends fed (outermost first), the puncture, the right
// ends — what the cut is measured against (cut_measure's Hausdorff distance).
std::vector<Vec3> tool_polyline(const SurfaceCutter& s);

}  // namespace phaco::corneal_incision
