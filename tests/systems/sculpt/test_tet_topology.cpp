// components/tet_topology: neighbours, boundary, volumes and the surface list of the lens tets.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "sculpt_fixture.hpp"

namespace phaco::sculpt::test {
namespace {

using Tri = std::array<uint32_t, 3>;

// Same cyclic order, smallest index first: equal for equal oriented triangles.
Tri canonical(Tri t) {
  while (t[0] > t[1] || t[0] > t[2]) t = {t[1], t[2], t[0]};
  return t;
}

TEST(TetTopology, TwoTetsShareOneFace) {
  TetMesh m;
  m.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1), Vec3(1, 1, 1)};
  m.tets = {{0, 1, 2, 3}, {4, 1, 3, 2}};  // second: apex 4 over the face (1, 2, 3)
  m.region = {0, 0};
  TetTopology topo = build_tet_topology(m);
  EXPECT_EQ(topo.neighbours[0][0], 1u);  // face opposite vertex 0 = (1, 2, 3)
  EXPECT_EQ(topo.neighbours[1][0], 0u);
  for (int k = 1; k < 4; ++k) EXPECT_EQ(topo.neighbours[0][k], kNoTet);
  EXPECT_NEAR(topo.volume[0], 1.0 / 6.0, 1e-7);
  EXPECT_GT(topo.volume[1], 0.0f);
  EXPECT_EQ(topo.surface.size(), 2u);
  std::vector<Tri> faces;
  surface_triangles(topo, faces);
  EXPECT_EQ(faces.size(), 6u);  // the shared face is interior
  remove_tet(topo, 0);
  EXPECT_EQ(topo.alive_count, 1u);
  EXPECT_EQ(topo.surface, std::vector<uint32_t>{1});
  surface_triangles(topo, faces);
  EXPECT_EQ(faces.size(), 4u);  // the shared face is exposed now
  remove_tet(topo, 1);
  EXPECT_TRUE(topo.surface.empty());
}

TEST(TetTopology, RejectsAFaceOfThreeTets) {
  TetMesh m;
  m.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0),
                Vec3(0, 0, 1), Vec3(1, 1, 1), Vec3(-1, -1, -1)};
  m.tets = {{0, 1, 2, 3}, {4, 1, 3, 2}, {5, 1, 3, 2}};
  EXPECT_THROW(build_tet_topology(m), std::invalid_argument);
}

TEST(TetTopology, LensNeighboursAreSymmetricAndShareTheirFace) {
  const TetMesh& mesh = lens_tets(0);
  const TetTopology topo = build_tet_topology(mesh);
  ASSERT_EQ(topo.tet_count, mesh.tets.size());
  for (uint32_t t = 0; t < topo.tet_count; ++t) {
    for (int k = 0; k < 4; ++k) {
      const uint32_t n = topo.neighbours[t][k];
      if (n == kNoTet) continue;
      const auto& back = topo.neighbours[n];
      const auto it = std::find(back.begin(), back.end(), t);
      ASSERT_NE(it, back.end()) << "tet " << t << " face " << k;
      std::set<uint32_t> mine, theirs;
      for (int j = 0; j < 3; ++j) mine.insert(mesh.tets[t][kTetFaceCorners[k][j]]);
      const int kk = static_cast<int>(it - back.begin());
      for (int j = 0; j < 3; ++j) theirs.insert(mesh.tets[n][kTetFaceCorners[kk][j]]);
      EXPECT_EQ(mine, theirs);
    }
  }
}

TEST(TetTopology, BoundaryFacesAreTheLensSurface) {
  const auto res = eye::resolution_for_level(0);
  const SurfaceMesh surface = eye::make_lens_surface(eye::default_eye_params(), res);
  const TetTopology topo = build_tet_topology(lens_tets(0));
  std::vector<Tri> faces;
  surface_triangles(topo, faces);
  ASSERT_EQ(faces.size(), surface.triangles.size());
  std::set<Tri> ours, tetgen;
  for (const Tri& f : faces) ours.insert(canonical(f));
  for (const Tri& f : surface.triangles) tetgen.insert(canonical(f));
  EXPECT_EQ(ours, tetgen);  // same triangles, same outward winding
  // Every surface tet owns at least one of those faces; no interior tet is listed.
  for (uint32_t t = 0; t < topo.tet_count; ++t)
    EXPECT_EQ(topo.surface_slot[t] != kNoTet, tet_on_surface(topo, t));
}

TEST(TetTopology, VolumesSumToTheLens) {
  const auto res = eye::resolution_for_level(0);
  const SurfaceMesh surface = eye::make_lens_surface(eye::default_eye_params(), res);
  const TetTopology topo = build_tet_topology(lens_tets(0));
  double tets = 0.0;
  for (float v : topo.volume) {
    EXPECT_GT(v, 0.0f);
    tets += v;
  }
  double enclosed = 0.0;  // divergence theorem over the closed surface
  for (const Tri& f : surface.triangles) {
    const Vec3 &a = surface.vertices[f[0]], &b = surface.vertices[f[1]],
               &c = surface.vertices[f[2]];
    enclosed += a.dot(b.cross(c)) / 6.0;
  }
  EXPECT_NEAR(tets, enclosed, 1e-5 * enclosed);
  const LensShape lens = lens_shape();
  const double ellipsoids =
      2.0 / 3.0 * 3.14159265358979 * lens.a * lens.a * (lens.c_anterior + lens.c_posterior);
  EXPECT_LT(tets, ellipsoids);  // inscribed polyhedron
  EXPECT_GT(tets, 0.95 * ellipsoids);
}

}  // namespace
}  // namespace phaco::sculpt::test
