#pragma once
// Undoing an inserted vertex: the inverse of split_face / split_edge, for the temporary vertex a
// forceps grasp inserts inside a triangle or on an edge (seed 000 §6.1, Fig. 9: "a vertex and the
// associated edges are created temporarily ... removed after the mesh is released";
// systems/cut/grasp_point.hpp).
//
// A recorded split remembers the star it leaves around the new vertex (the triangle slots holding
// it, their corners in order, their links across the edges through it) and the original triangles
// it replaced (slot and corners). The vertex is removed only while that star is exactly as
// recorded, i.e. nothing has split, opened or duplicated an edge through it since; the original
// triangles then come back in their original slots (the other pieces are tombstoned), linked to
// today's outer neighbours, the vertex's springs are removed and a split edge's spring comes back
// (in a fresh or recycled slot), and the corners' hints point at the restored triangles. As after
// any edit, the caller then refreshes stiffness, rest lengths and masses (refresh_region over
// log.touched_triangles), which gives back the values the region had before the split.
//
// A record names table slots: it does not survive table compaction (remove or forget it first).
#include <array>
#include <cstdint>

#include "systems/cut/membrane_edit.hpp"

namespace phaco::cut {

struct VertexInsertion {
  CutPoint::Kind kind = CutPoint::Vertex;  // Face: by split_face; Edge: by split_edge; Vertex: none
  uint32_t vertex = kInvalidIndex;         // the inserted particle
  uint32_t a = kInvalidIndex, b = kInvalidIndex;  // Edge: the split edge's ends, as given
  Vec3 weights = Vec3::Zero();  // Face: of original_corners[0]; Edge: (1-t, t, 0) of (a, b)
  uint32_t original_count = 0;  // 1 (a face, or an edge on the rim or a cut lip) or 2
  std::array<uint32_t, 2> original_slot{kInvalidIndex, kInvalidIndex};
  std::array<std::array<uint32_t, 3>, 2> original_corners{};
  uint32_t piece_count = 0;  // 3 (face), 2 or 4 (edge)
  std::array<uint32_t, 4> piece_slot{kInvalidIndex, kInvalidIndex, kInvalidIndex, kInvalidIndex};
  std::array<std::array<uint32_t, 3>, 4> piece_corners{};
  std::array<std::array<uint32_t, 3>, 4>
      piece_links{};  // across edge k; checked where it holds the vertex
};

// Two triangles hold edge (a, b) but are not neighbours across it (a slit, or an opened cut whose
// ends share the edge): splitting it would open the new point at once (split_edge separates it).
bool is_slit(const CutMesh& m, uint32_t a, uint32_t b);

// split_face / split_edge, recorded. split_edge_recorded throws std::invalid_argument on a slit
// (its split cannot be undone) as well as where split_edge does.
VertexInsertion split_face_recorded(CutMesh& m, uint32_t tri, const Vec3& bary, EditLog& log);
VertexInsertion split_edge_recorded(CutMesh& m, uint32_t a, uint32_t b, double t, EditLog& log);

enum class InsertionState : uint8_t {
  Intact,      // the star is as the split left it: the vertex can be removed
  Changed,     // a piece died or changed corners, or an edge through the vertex was opened
  Degenerate,  // restoring would give a triangle below the invariants' area (1e-8 mm²) or angle
               // (1°) in the current shape
  Gone,        // the vertex is dead (e.g. merged away by remeshing) or nothing was inserted
};
InsertionState insertion_state(const CutMesh& m, const VertexInsertion& ins);

// Removes the inserted vertex and restores the original triangles if insertion_state is Intact;
// returns false (and changes nothing) otherwise. Logs the vertex in removed_particles and the
// restored triangles in touched_triangles.
bool remove_inserted_vertex(CutMesh& m, const VertexInsertion& ins, EditLog& log);

// Smallest angle (degrees, over the current and the rest shape) the triangles would have after
// inserting a point at weights `bary` in triangle `tri`, or at (1-t)·a + t·b on edge (a, b); the
// cutter's quality snap measure (0 if (a, b) is not an edge).
double face_split_min_angle(const CutMesh& m, uint32_t tri, const Vec3& bary);
double edge_split_min_angle(const CutMesh& m, uint32_t a, uint32_t b, double t);

}  // namespace phaco::cut
