// Boundary surface by traversing boundary links (seed 002 §5.2) and the plain external faces.
#include <gtest/gtest.h>

#include <map>
#include <random>

#include "procedures/eye/eye_mesh.hpp"
#include "procedures/eye/eye_params.hpp"
#include "procedures/eye/resolution.hpp"
#include "systems/simplex/simplex_cells.hpp"
#include "systems/simplex/simplex_surface.hpp"
#include "tests/systems/simplex/simplex_meshes.hpp"

namespace phaco::simplex {
namespace {

double signed_volume(const BoundarySurface& s) {
  double v = 0;
  for (const auto& t : s.triangles) {
    const Vec3 a(s.x[t[0]], s.y[t[0]], s.z[t[0]]), b(s.x[t[1]], s.y[t[1]], s.z[t[1]]),
        c(s.x[t[2]], s.y[t[2]], s.z[t[2]]);
    v += a.dot(b.cross(c)) / 6.0;
  }
  return v;
}

double signed_volume(const SurfaceMesh& s) {
  double v = 0;
  for (const auto& t : s.triangles)
    v += s.vertices[t[0]].dot(s.vertices[t[1]].cross(s.vertices[t[2]])) / 6.0;
  return v;
}

double alive_volume(const SimplexCells& cells, const TetMesh& mesh) {
  double v = 0;
  for (uint32_t c = 0; c < cells.size(); ++c) {
    if (!cells.alive[c]) continue;
    const auto& t = mesh.tets[c];
    v += (mesh.vertices[t[1]] - mesh.vertices[t[0]])
             .dot((mesh.vertices[t[2]] - mesh.vertices[t[0]])
                      .cross(mesh.vertices[t[3]] - mesh.vertices[t[0]])) /
         6.0;
  }
  return v;
}

// Each directed edge once and its reverse once: closed and consistently oriented.
uint32_t orientation_defects(const std::vector<std::array<uint32_t, 3>>& triangles) {
  std::map<std::pair<uint32_t, uint32_t>, int> directed;
  for (const auto& t : triangles)
    for (int i = 0; i < 3; ++i) ++directed[{t[i], t[(i + 1) % 3]}];
  uint32_t defects = 0;
  for (const auto& [e, count] : directed) {
    const auto back = directed.find({e.second, e.first});
    defects += count != 1 || back == directed.end() || back->second != 1;
  }
  return defects;
}

TEST(SimplexSurface, LoneCellIsAClosedTetOfFaceCentres) {
  const SimplexCells cells = build_cells(testing::one_tet());
  BoundarySurface s;
  build_boundary_surface(cells, s);
  EXPECT_EQ(s.x.size(), 4u);  // rings of three need no centre node
  ASSERT_EQ(s.triangles.size(), 4u);
  EXPECT_EQ(s.broken_rings, 0u);
  EXPECT_EQ(orientation_defects(s.triangles), 0u);
  // The tet of face centres is the original scaled by −1/3: volume (1/6)/27.
  EXPECT_NEAR(signed_volume(s), 1.0 / 6.0 / 27.0, 1e-7);
  for (uint32_t i = 0; i < 4; ++i) {
    const Vec3 out(s.x[i] - cells.x[0], s.y[i] - cells.y[0], s.z[i] - cells.z[0]);
    EXPECT_GT(out.dot(Vec3(s.nx[i], s.ny[i], s.nz[i])), 0.0)
        << "node normal " << i << " points inward";
  }
}

TEST(SimplexSurface, LensDualSurfaceIsClosedOutwardAndFollowsTheCells) {
  const TetMesh mesh = eye::make_lens_tets(eye::default_eye_params(), eye::resolution_for_level(0));
  SimplexCells cells = build_cells(mesh);
  BoundarySurface s;
  build_boundary_surface(cells, s);
  EXPECT_EQ(s.face_nodes, count_external_faces(cells));
  EXPECT_EQ(s.broken_rings, 0u);
  EXPECT_EQ(orientation_defects(s.triangles), 0u);
  const double lens = alive_volume(cells, mesh);
  const double dual = signed_volume(s);
  EXPECT_GT(dual, 0.9 * lens);  // face centres sit just inside the tet surface
  EXPECT_LT(dual, lens);
  // A closed sphere: Euler characteristic V − E + T = 2 with E = 3T/2.
  EXPECT_EQ(static_cast<int64_t>(s.x.size()) - static_cast<int64_t>(s.triangles.size()) / 2, 2);

  const float shift[3] = {0.5f, -1.0f, 2.0f};
  for (uint32_t c = 0; c < cells.size(); ++c)
    cells.x[c] += shift[0], cells.y[c] += shift[1], cells.z[c] += shift[2];
  BoundarySurface moved;
  build_boundary_surface(cells, moved);
  ASSERT_EQ(moved.x.size(), s.x.size());
  for (size_t i = 0; i < s.x.size(); i += 97) {
    EXPECT_NEAR(moved.x[i] - s.x[i], shift[0], 1e-5);
    EXPECT_NEAR(moved.z[i] - s.z[i], shift[2], 1e-5);
  }
}

TEST(SimplexSurface, ExternalFacesEncloseTheAliveVolumeThroughRemovals) {
  const TetMesh mesh = eye::make_lens_tets(eye::default_eye_params(), eye::resolution_for_level(0));
  SimplexCells cells = build_cells(mesh);
  SurfaceMesh faces;
  BoundarySurface dual;
  std::mt19937 rng(11);
  const auto order = testing::random_order(cells.size(), rng);
  for (uint32_t i = 0; i < order.size(); ++i) {
    if (i % 700 == 0) {
      extract_external_faces(cells, mesh.vertices, faces);
      const double alive = alive_volume(cells, mesh);
      EXPECT_NEAR(signed_volume(faces), alive, 1e-9 * (1.0 + alive))
          << "after " << i << " removals";
      build_boundary_surface(cells, dual);
      EXPECT_EQ(dual.broken_rings, 0u);
      EXPECT_EQ(orientation_defects(dual.triangles), 0u) << "after " << i << " removals";
    }
    remove_cell(cells, order[i]);
  }
  extract_external_faces(cells, mesh.vertices, faces);
  EXPECT_TRUE(faces.triangles.empty());
  build_boundary_surface(cells, dual);
  EXPECT_TRUE(dual.triangles.empty());
  EXPECT_TRUE(dual.x.empty());
}

}  // namespace
}  // namespace phaco::simplex
