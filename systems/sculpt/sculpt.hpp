#pragma once
// Tetrahedral sculpting of the lens by the phaco tip (seed 000 §5.3).
//
// One step removes every alive tet the tip hits this step, the tip being the capsule its sphere
// sweeps from the previous to the current centre (radius from the ultrasound power,
// sculpt_radius_mm). How the tets are found:
//
//   seeds  = last removals whose bounding sphere touches the tip ("removal continues from the
//            last removed tets"), kept only if one of them truly meets the tip (centre test or
//            exact convex test); otherwise
//   seeds  = broadphase candidates (octree or btDbvt): the first contact.
//   walk   = breadth-first over face neighbours from the seeds, through every tet (alive or
//            already removed) whose bounding sphere touches the tip; each alive tet visited is
//            removed when the narrowphase says so.
//
// Why the walk passes through removed tets and tets that fail the narrowphase: the tets of a
// convex domain that meet a convex shape are face-connected (follow the segment between two of
// them), and every one of them passes the bounding-sphere test, so one true seed reaches all of
// them. A walk through narrowphase hits only would stop at a tet whose centre falls outside the
// tip while tets beyond it still qualify, or at the trench the tip has already dug. Cost is the
// tets near the tip, independent of the mesh size; the broadphase runs only when the tip has
// nothing to continue from.
//
// Surface list: a removed tet leaves it, its alive neighbours join it (components/tet_topology).
// The step is serial: it touches a few hundred tets; its order (candidates sorted by index, then
// breadth-first) is fixed, so both broadphases give the same removals in the same order.
//
// Reads: lens vertex positions (lens frame, mm), the tip. Writes: TetTopology (alive, surface
// list, counts), the broadphase's own tree, the state's scratch. No allocation once the scratch
// vectors have grown to the largest step.
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "components/tet_topology.hpp"
#include "engine/core/math.hpp"
#include "systems/sculpt/broadphase.hpp"
#include "systems/sculpt/tip_contact.hpp"

namespace phaco::sculpt {

inline constexpr double kPhacoTipRadiusMm = 0.45;  // outer diameter 0.9 (DESIGN.md §6)

// Ultrasound power as the removal radius: nothing below pedal position 3 (no ultrasound), then
// r = r_tip·(0.5 + 0.5·power) for power in [0, 1] (clamped): half the tip at the lowest power,
// the full tip at full power.
double sculpt_radius_mm(double pedal, double power, double tip_radius_mm = kPhacoTipRadiusMm);

struct SculptOptions {
  Broadphase broadphase = Broadphase::Octree;
  Narrowphase narrowphase = Narrowphase::CentreInSphere;
  bool continue_from_last = true;  // false: the broadphase seeds every step
  uint32_t octree_leaf_capacity = 32;
};

struct SculptTip {
  Vec3 centre = Vec3::Zero();           // mm, lens frame, this step
  Vec3 previous_centre = Vec3::Zero();  // mm, last step (equal to centre for a resting tip)
  double radius_mm = 0.0;
};

struct SculptStats {
  bool used_broadphase = false;
  BroadphaseStats broadphase;
  uint32_t candidates = 0;         // broadphase output
  uint32_t seeds = 0;              // walk start tets
  uint32_t walk_visits = 0;        // tets taken from the walk queue
  uint32_t neighbour_tests = 0;    // bounding-sphere tests of neighbours
  uint32_t narrowphase_tests = 0;  // alive tets tested
  uint32_t removed = 0;
  // Everything the step looked at: tree nodes, leaf entries, walk tests.
  uint32_t work() const {
    return broadphase.nodes_visited + broadphase.tets_scanned + seeds + neighbour_tests;
  }
};

struct SculptState {
  SculptOptions options;
  TetOctree octree;               // built when options.broadphase == Octree
  TetDbvt dbvt;                   // built when options.broadphase == Dbvt
  std::vector<uint32_t> removed;  // this step's removals, in removal order
  std::vector<uint32_t> seeds;    // the last non-empty removal set
  std::vector<uint32_t> visit_stamp;
  uint32_t stamp = 0;
  std::vector<uint32_t> queue, candidates, tree_queue;
  SculptStats stats;
};

SculptState make_sculpt_state(const TetTopology& topo, const SculptOptions& options);

// Removes the tets the tip hits this step; returns them (valid until the next step).
std::span<const uint32_t> sculpt_step(TetTopology& topo, std::span<const Vec3> positions,
                                      SculptState& state, const SculptTip& tip);

// The faces to render: every face of a surface tet with no alive neighbour, outward-wound.
void surface_triangles(const TetTopology& topo, std::vector<std::array<uint32_t, 3>>& out);

}  // namespace phaco::sculpt
