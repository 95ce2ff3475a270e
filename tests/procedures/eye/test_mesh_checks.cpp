#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "engine/core/error.hpp"
#include "engine/core/mesh_checks.hpp"
#include "tests/support/fan_meshes.hpp"

namespace phaco {
namespace {

// Unit right-corner tetrahedron as a closed outward surface.
SurfaceMesh tetra_surface() {
  SurfaceMesh m;
  m.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return m;
}

// Two triangles forming a unit square in z = 0, facing +z.
SurfaceMesh square() {
  SurfaceMesh m;
  m.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0)};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

TEST(MeshChecks, ClosedTetrahedron) {
  const SurfaceTopology t = check_surface(tetra_surface());
  EXPECT_TRUE(t.closed());
  EXPECT_TRUE(t.manifold());
  EXPECT_TRUE(t.oriented());
  EXPECT_EQ(t.edges, 6u);
  EXPECT_EQ(t.euler(), 2);
  EXPECT_EQ(t.boundary_loops, 0u);
  EXPECT_EQ(t.degenerate_triangles, 0u);
  EXPECT_NEAR(signed_volume(tetra_surface()), 1.0 / 6.0, 1e-15);
}

TEST(MeshChecks, FlippedTriangleIsInconsistent) {
  SurfaceMesh m = tetra_surface();
  std::swap(m.triangles[3][1], m.triangles[3][2]);
  const SurfaceTopology t = check_surface(m);
  EXPECT_FALSE(t.oriented());
  EXPECT_EQ(t.inconsistent_edges, 3u);
  EXPECT_TRUE(t.closed());
}

TEST(MeshChecks, OpenSquareHasOneBoundaryLoop) {
  const SurfaceTopology t = check_surface(square());
  EXPECT_FALSE(t.closed());
  EXPECT_EQ(t.boundary_edges, 4u);
  EXPECT_EQ(t.boundary_loops, 1u);
  EXPECT_EQ(t.euler(), 1);
}

TEST(MeshChecks, ThreeTrianglesOnAnEdgeAreNonManifold) {
  SurfaceMesh m = square();
  m.vertices.emplace_back(0.5, 0.5, 1.0);
  m.triangles.push_back({0, 2, 4});
  const SurfaceTopology t = check_surface(m);
  EXPECT_EQ(t.nonmanifold_edges, 1u);
  EXPECT_FALSE(t.manifold());
}

TEST(MeshChecks, BowtieVertexIsNonManifold) {
  SurfaceMesh m;
  m.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(-1, 0, 0), Vec3(-1, -1, 0)};
  m.triangles = {{0, 1, 2}, {0, 3, 4}};
  const SurfaceTopology t = check_surface(m);
  EXPECT_EQ(t.nonmanifold_edges, 0u);
  EXPECT_EQ(t.nonmanifold_vertices, 1u);
  EXPECT_FALSE(t.manifold());
  EXPECT_EQ(t.boundary_loops, 1u);  // the two loops touch at vertex 0
}

// Hand-made fans around vertex 0 (tests/support/fan_meshes.hpp): only one disc or one half-disc
// is manifold; two fans meeting only at the vertex are one non-manifold vertex whether they are
// boundary fans or closed discs.
TEST(MeshChecks, EachVertexIsOneDiscOrOneHalfDisc) {
  for (const test::FanMesh& f : test::fan_meshes()) {
    SCOPED_TRACE(f.name);
    const SurfaceTopology t = check_surface(f.mesh);
    EXPECT_EQ(t.nonmanifold_edges, 0u);
    EXPECT_EQ(t.nonmanifold_vertices, f.fans_at_0 == 1 ? 0u : 1u);
    EXPECT_EQ(t.manifold(), f.fans_at_0 == 1);
    EXPECT_EQ(t.degenerate_triangles, 0u);
  }
}

TEST(MeshChecks, DegenerateAndUnreferencedAreCounted) {
  SurfaceMesh m = square();
  m.vertices.emplace_back(2, 0, 0);
  m.vertices.emplace_back(7, 7, 7);
  m.triangles.push_back({0, 1, 4});  // collinear
  const SurfaceTopology t = check_surface(m);
  EXPECT_EQ(t.degenerate_triangles, 1u);
  EXPECT_EQ(t.unreferenced_vertices, 1u);
}

TEST(MeshChecks, OutOfRangeIndexThrows) {
  SurfaceMesh m = square();
  m.triangles.push_back({0, 1, 9});
  EXPECT_THROW(check_surface(m), InputError);
}

TEST(MeshChecks, TetVolumesAndQuality) {
  const Vec3 a(1, 1, 1), b(1, -1, -1), c(-1, 1, -1), d(-1, -1, 1);  // regular, edge 2√2
  const double v = tet_signed_volume(a, b, c, d);
  EXPECT_NEAR(std::abs(v), 8.0 / 3.0, 1e-12);
  EXPECT_NEAR(tet_signed_volume(a, b, d, c), -v, 1e-12);
  EXPECT_NEAR(tet_radius_edge_ratio(a, b, c, d), std::sqrt(6.0) / 4.0, 1e-12);
  EXPECT_NEAR(tet_min_dihedral_deg(a, b, c, d), std::acos(1.0 / 3.0) * 180.0 / std::numbers::pi,
              1e-9);
  // A sliver: four nearly coplanar points on a square.
  EXPECT_LT(tet_min_dihedral_deg(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0.01), Vec3(0, 1, 0)),
            2.0);
  // The corner tet has right dihedral angles at the origin and 54.7° on the slanted face.
  EXPECT_NEAR(tet_min_dihedral_deg(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)),
              std::acos(1.0 / std::sqrt(3.0)) * 180.0 / std::numbers::pi, 1e-9);

  TetMesh mesh;
  mesh.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1), Vec3(1, 1, 1)};
  mesh.tets = {{0, 1, 2, 3}, {1, 3, 2, 4}};
  mesh.region = {0, 0};
  TetQuality q = check_tets(mesh);
  EXPECT_EQ(q.nonpositive, 1u) << "the second tet is inverted";
  EXPECT_NEAR(q.min_volume, -1.0 / 3.0, 1e-12);
  mesh.tets[1] = {1, 2, 3, 4};
  q = check_tets(mesh);
  EXPECT_EQ(q.nonpositive, 0u);
  EXPECT_NEAR(q.total_volume, 1.0 / 6.0 + 1.0 / 3.0, 1e-12);
  mesh.tets[1] = {1, 3, 2, 5};
  EXPECT_THROW(check_tets(mesh), InputError);
}

}  // namespace
}  // namespace phaco
