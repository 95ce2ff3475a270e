#pragma once
// The lens as simplex cells (seed 002 §5): one cell per tetrahedron, the tet's dual. A cell has a
// centre (a particle of the lens simulation), up to four internal neighbours (the cells sharing a
// face), and for each of its EXTERNAL faces the boundary links: the three boundary faces that share
// an edge with it on the boundary surface (seed 002 Fig. 4, "boundary simplex representation").
//
// Faces and edges are numbered from the original tet (kept per cell):
//   face k of a cell   = the tet face opposite local vertex k; its corners, counter-clockwise seen
//                        from outside the tet, are kTetFaceCorners[k];
//   edge slot j of k   = the edge opposite corner j of that face (corners (j+1)%3 and (j+2)%3);
//   face id            = cell * 4 + k (one 32-bit index names a (simplex, face) pair).
// A face is external when the cell is alive and has no neighbour across it.
//
// Plain data: built by systems/simplex (build_cells); its topology columns are changed only by the
// removal primitive there (remove_cell), the centres x, y, z by the dynamics.
#include <array>
#include <cstdint>
#include <vector>

#include "components/tets.hpp"  // kTetFaceCorners

namespace phaco {

inline constexpr uint32_t kNoSimplex = 0xffffffffu;  // "no cell" / "no face" in any index column

// kTetCornerSlot[k][v]: position of local vertex v among face k's corners (v != k), 3 for v == k.
inline constexpr std::array<std::array<uint8_t, 4>, 4> kTetCornerSlot = {
    {{3, 0, 1, 2}, {0, 3, 2, 1}, {0, 1, 3, 2}, {0, 2, 1, 3}}};

constexpr uint32_t simplex_face_id(uint32_t cell, uint32_t face) {
  return cell * 4u + face;
}
constexpr uint32_t simplex_face_cell(uint32_t face_id) {
  return face_id >> 2;
}
constexpr uint32_t simplex_face_local(uint32_t face_id) {
  return face_id & 3u;
}

struct SimplexCells {
  // Per cell (index = tet index of the mesh it was built from).
  std::vector<float> x, y, z;                      // centre now, mm
  std::vector<float> rest_x, rest_y, rest_z;       // centre at rest (tet centroid), mm
  std::vector<float> volume;                       // rest tet volume, mm³
  std::vector<float> mass;                         // kg (volume × density at build)
  std::vector<std::array<uint32_t, 4>> neighbour;  // cell across face k; kNoSimplex if none
  std::vector<std::array<uint8_t, 4>>
      neighbour_face;  // that neighbour's face index (valid if neighbour)
  // boundary_link[c][3k + j]: face id of the boundary face sharing edge slot j of face k; set for
  // external faces of alive cells, kNoSimplex otherwise.
  std::vector<std::array<uint32_t, 12>> boundary_link;
  std::vector<uint8_t> alive;                // 1 alive, 0 removed
  std::vector<uint8_t> region;               // 1 nucleus, 0 cortex (from the tet)
  std::vector<std::array<uint32_t, 4>> tet;  // original tet's vertex ids (consistency checks)
  // Per face id (4 per cell): the face's centre at rest, mm (used by the boundary triangulation).
  std::vector<float> face_x, face_y, face_z;
  uint32_t alive_count = 0;

  uint32_t size() const { return static_cast<uint32_t>(x.size()); }
  bool is_external(uint32_t cell, uint32_t face) const {
    return alive[cell] != 0 && neighbour[cell][face] == kNoSimplex;
  }
  uint32_t link(uint32_t face_id, uint32_t slot) const {
    return boundary_link[simplex_face_cell(face_id)][3 * simplex_face_local(face_id) + slot];
  }
};

}  // namespace phaco
