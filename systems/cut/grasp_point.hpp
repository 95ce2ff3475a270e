#pragma once
// Forceps grasp of a membrane at any surface point, seed 000 §6.1 and Fig. 9: "the grasped point
// can be regarded as a mesh vertex (trivial case), a point within a triangle or on the edge of a
// triangle, depending on its proximity to mesh vertices or edges. To simulate the last two
// scenarios, especially necessary when the mesh is of low resolution, a vertex and the associated
// edges are created temporarily to represent the grasped point ... The temporary vertex and edges
// are removed after the mesh is released."
//
//   (a) at a vertex      (b) inside a triangle      (c) on an edge
//
//          c                     c                        c
//         / \                   /|\                      /|\      (a) nothing inserted
//        /   \                 / q \                    / | \     (b) split_face: q joined to
//       a-----b               a-----b                  a--q--b       a, b, c (3 triangles)
//                                                       \ | /     (c) split_edge: q joined to
//                                                        \|/          a, b, c, d (4 triangles;
//                                                         d           2 on the rim)
//
// Where: the surface point (a CutPoint, already proximity-snapped by locate_cut_point with the
// cutter's SnapSettings) is then held to the cutter's quality rule (CutSettings::min_angle_deg):
// a split that would leave a sliver goes to the nearest edge, then the nearest corner, so a grasp
// never creates a triangle the invariants reject. A slit edge is grasped at its nearer end (its
// split would open at once and could not be undone), and a wholly anchored feature is not grasped.
//
// Release: the temporary vertex is removed and the original triangle(s) come back with their
// adjacency, hints and springs (a split edge's spring returns), stiffness, rest lengths and masses
// refreshed from the rest shape — the values they had before the grasp — while the local topology
// is what the grasp made. If a cut or tear has gone through the vertex meanwhile (or restoring
// would make a degenerate triangle in the current shape) it stays, as an ordinary vertex of the
// membrane, and the report says so.
//
// Momentum on release: the removed vertex's momentum m_q·v_q is handed to the original corners in
// the proportions of its rest-shape weights (the same proportions its lumped mass returns to them),
// v_i ← (m_i·v_i + w_i·m_q·v_q) / m_i' with m_i' the corner's refreshed mass; so the free corners
// together carry what they carried plus the vertex's momentum, nothing is lost at the instant of
// release. A corner that is anchored or scripted keeps its imposed velocity and its share goes to
// the anchor or the tool. The vertex's position is not carried over: the stretch it held relaxes
// through the restored springs in the next steps (the surface is no longer tented at that point).
//
// What this does not do: hold the particle. The forceps' motion (the held particle made scripted
// and moved with the tip, seed 001 §3.4) is systems/grasp's; the scene passes it `particle`.
//
// Reads and writes: <body>.particles, <body>.triangles, <body>.springs, the MembraneTopology.
#include <cstdint>

#include "systems/cut/membrane_edit.hpp"
#include "systems/cut/progressive_cut.hpp"
#include "systems/cut/vertex_insertion.hpp"

namespace phaco::cut {

struct GraspPoint {
  uint32_t particle = kInvalidIndex;       // the particle the forceps hold; kInvalidIndex: nothing
  CutPoint::Kind kind = CutPoint::Vertex;  // where it was grasped, after snapping (Fig. 9 a, b, c)
  bool temporary = false;     // particle was inserted for this grasp (kind Face or Edge)
  VertexInsertion insertion;  // temporary: the original triangle(s) or edge, and the pieces
  double moved_mm = 0.0;      // how far the quality snap moved the point
  bool held() const { return particle != kInvalidIndex; }
};

// Grasps the membrane at `where` (see above); refreshes springs and masses around an inserted
// vertex. Throws std::invalid_argument if `where` names a dead triangle or particle or has a
// non-finite position.
GraspPoint grasp_at(CutMesh& mesh, const CutPoint& where, const CutSettings& settings,
                    EditLog& log);

// The same at the surface point nearest the forceps tip (locate_cut_point from start_triangle).
GraspPoint grasp_near(CutMesh& mesh, const Vec3& tip, uint32_t start_triangle,
                      const CutSettings& settings, EditLog& log);

struct ReleaseReport {
  bool released = false;  // something was held
  bool removed_temporary =
      false;                    // the temporary vertex is gone, the original triangle(s) restored
  bool kept_temporary = false;  // the temporary vertex stays as a regular vertex (see state)
  InsertionState state = InsertionState::Gone;  // temporary: what release found
};

// Lets go: removes a temporary vertex whose star is intact (refreshing springs and masses, handing
// on its momentum), keeps it otherwise. The grasp is cleared (particle = kInvalidIndex).
ReleaseReport release(CutMesh& mesh, GraspPoint& grasp, EditLog& log);

}  // namespace phaco::cut
