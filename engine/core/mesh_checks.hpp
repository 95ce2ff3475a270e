#pragma once
// Generic mesh invariants: topology of a triangle surface (closed, manifold, oriented, boundary
// loops) and volume/quality of a tetrahedral mesh. Generators test their output with these, and
// the cut/tear code checks that topology changes keep them.
#include <cstddef>

#include "engine/core/math.hpp"
#include "engine/core/mesh_data.hpp"

namespace phaco {

struct SurfaceTopology {
  size_t vertices = 0;  // all vertices in the mesh, referenced or not
  size_t edges = 0;     // distinct undirected edges
  size_t triangles = 0;
  size_t boundary_edges = 0;      // edges used by exactly one triangle
  size_t nonmanifold_edges = 0;   // edges used by more than two triangles
  size_t inconsistent_edges = 0;  // an interior edge traversed the same direction by both triangles
  size_t nonmanifold_vertices = 0;  // triangles around the vertex form more than one fan
  size_t boundary_loops = 0;        // connected components of the boundary edges
  size_t degenerate_triangles = 0;  // repeated vertex or (near) zero area
  size_t unreferenced_vertices = 0;

  bool closed() const { return boundary_edges == 0; }
  bool manifold() const { return nonmanifold_edges == 0 && nonmanifold_vertices == 0; }
  bool oriented() const { return inconsistent_edges == 0; }
  // V - E + F over referenced vertices: 2 for a sphere, 1 for a disc, 0 for an annulus.
  int euler() const {
    return static_cast<int>(vertices - unreferenced_vertices) - static_cast<int>(edges) +
           static_cast<int>(triangles);
  }
};

// Throws InputError if a triangle refers to a vertex index outside the mesh.
SurfaceTopology check_surface(const SurfaceMesh& mesh);

// Divergence theorem; > 0 for an outward-oriented closed mesh.
double signed_volume(const SurfaceMesh& mesh);

// (b-a)·((c-a)×(d-a)) / 6; > 0 for the positive orientation of TetMesh.
double tet_signed_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

// Circumradius divided by the shortest edge (TetGen's quality measure; 0.612 for a regular tet).
double tet_radius_edge_ratio(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

// Smallest of the six dihedral angles, degrees (70.5 for a regular tet, near 0 for a sliver).
double tet_min_dihedral_deg(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

struct TetQuality {
  double min_volume = 0.0;        // mm³
  double total_volume = 0.0;      // mm³
  double max_radius_edge = 0.0;   // circumradius / shortest edge
  double min_dihedral_deg = 0.0;  // smallest dihedral angle over all tets
  size_t nonpositive = 0;         // tets with volume <= 0
};

// Throws InputError if a tet refers to a vertex index outside the mesh.
TetQuality check_tets(const TetMesh& mesh);

}  // namespace phaco
