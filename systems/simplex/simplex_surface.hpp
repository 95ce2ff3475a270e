#pragma once
// Boundary surface of the simplex cells (seed 002 §5.2) and the plain external-face extraction.
//
// The seed's triangulation traverses the boundary links: one surface node per boundary element,
// triangles by looping over the links about each node, then normals. Our node is one per EXTERNAL
// FACE, at the face's centre (carried with its cell: cell centre now + (face centre − cell centre)
// at rest), not one per boundary simplex at the simplex centre, because
//   - the boundary links join faces, not cells: the link graph is 3-regular on the external faces,
//     and its cycles about each boundary vertex are exactly the polygons of the dual surface;
//   - a simplex with two or three external faces would otherwise collapse those polygons, and a
//     single free cell (four external faces) or a one-cell-thick slab would render as nothing;
//     with face nodes a lone cell is a small closed tetrahedron.
// Triangles: for each boundary vertex, the ring of external faces about it (follow the link across
// the edge from the vertex to the next corner of the face); a ring of three faces is one triangle,
// a longer ring is fanned from an extra node at its centre (the mean of its face nodes, close to
// the vertex). A vertex where two runs of solid touch has one ring per run, so the surface is
// closed and consistently oriented even where the solid touches itself along an edge or at a
// vertex. Normals: per triangle, and per node the area-weighted sum of its triangles' normals.
//
// Reads: SimplexCells (x, y, z, rest centres, face centres, neighbours, boundary links).
// Writes: BoundarySurface / SurfaceMesh (outputs only).
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "components/simplices.hpp"
#include "engine/core/mesh_data.hpp"

namespace phaco::simplex {

struct BoundarySurface {
  std::vector<uint32_t> node_face;  // face id of each node; kNoSimplex for ring centres
  uint32_t face_nodes = 0;          // nodes [0, face_nodes) are the external faces
  std::vector<float> x, y, z;       // node position, mm
  std::vector<float> nx, ny, nz;    // unit node normal (outward)
  std::vector<std::array<uint32_t, 3>> triangles;  // node indices, counter-clockwise from outside
  std::vector<float> tri_nx, tri_ny, tri_nz;       // unit triangle normal
  uint32_t broken_rings = 0;                       // rings that did not close (a broken structure)
  // Scratch reused between calls.
  std::vector<uint32_t> node_of_face;  // 4 per cell, kNoSimplex for internal faces
  std::vector<uint8_t> visited;        // per node, one bit per corner
  std::vector<uint32_t> ring;
};

// Builds the dual boundary surface from the boundary links. Allocates only when the surface grows.
void build_boundary_surface(const SimplexCells& cells, BoundarySurface& out);

// The external faces as triangles over the original tet vertices (counter-clockwise from outside),
// for rendering the lens at rest; `vertices` are the tet mesh's, copied to out.vertices.
void extract_external_faces(const SimplexCells& cells, std::span<const Vec3> vertices,
                            SurfaceMesh& out);

}  // namespace phaco::simplex
