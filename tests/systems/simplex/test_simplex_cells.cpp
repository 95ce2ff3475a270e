// Simplex cells: construction (seed 002 §5.1) and each case of the removal primitive (§5.3) on
// hand-made meshes, checked link by link and against the rebuild.
#include <gtest/gtest.h>

#include <set>
#include <stdexcept>

#include "procedures/eye/eye_mesh.hpp"
#include "procedures/eye/eye_params.hpp"
#include "procedures/eye/resolution.hpp"
#include "systems/simplex/simplex_cells.hpp"
#include "systems/simplex/simplex_fragments.hpp"
#include "tests/systems/simplex/simplex_meshes.hpp"

namespace phaco::simplex {
namespace {

using testing::cube_five;
using testing::kuhn_grid;
using testing::one_tet;
using testing::two_tets;

// Global vertex pair of edge slot j of face k of cell c, sorted.
std::pair<uint32_t, uint32_t> edge_of(const SimplexCells& cells, uint32_t c, uint32_t k,
                                      uint32_t j) {
  const uint32_t a = cells.tet[c][kTetFaceCorners[k][(j + 1) % 3]];
  const uint32_t b = cells.tet[c][kTetFaceCorners[k][(j + 2) % 3]];
  return {std::min(a, b), std::max(a, b)};
}

// Every link of an external face must name a face of the same cell (a lone cell's surface).
bool links_stay_in_cell(const SimplexCells& cells, uint32_t c) {
  for (uint32_t k = 0; k < 4; ++k)
    for (uint32_t j = 0; j < 3; ++j)
      if (simplex_face_cell(cells.boundary_link[c][3 * k + j]) != c) return false;
  return true;
}

TEST(SimplexCells, FaceTablesAreOutwardAndSlotsMatchCorners) {
  const TetMesh m = one_tet();
  const auto& t = m.tets[0];
  for (uint32_t k = 0; k < 4; ++k) {
    const auto& fc = kTetFaceCorners[k];
    const Vec3 a = m.vertices[t[fc[0]]], b = m.vertices[t[fc[1]]], c = m.vertices[t[fc[2]]];
    const Vec3 normal = (b - a).cross(c - a);
    EXPECT_LT(normal.dot(m.vertices[t[k]] - a), 0.0)
        << "face " << k << " must face away from vertex " << k;
    for (uint32_t s = 0; s < 3; ++s) EXPECT_EQ(kTetCornerSlot[k][fc[s]], s);
    EXPECT_EQ(kTetCornerSlot[k][k], 3);
  }
}

TEST(SimplexCells, OneTetIsALoneCellWhoseFacesLinkToEachOther) {
  SimplexCells cells = build_cells(one_tet());
  ASSERT_EQ(cells.size(), 1u);
  EXPECT_NEAR(cells.volume[0], 1.0 / 6.0, 1e-7);
  EXPECT_NEAR(cells.rest_x[0], 0.25, 1e-7);
  EXPECT_EQ(count_external_faces(cells), 4u);
  for (uint32_t k = 0; k < 4; ++k)
    for (uint32_t j = 0; j < 3; ++j) {
      const uint32_t other = cells.boundary_link[0][3 * k + j];
      ASSERT_NE(other, kNoSimplex);
      EXPECT_NE(simplex_face_local(other), k);
      // The linked face holds the same edge.
      bool shares = false;
      for (uint32_t pj = 0; pj < 3; ++pj)
        shares |= edge_of(cells, 0, simplex_face_local(other), pj) == edge_of(cells, 0, k, j);
      EXPECT_TRUE(shares);
    }
  EXPECT_TRUE(check_boundary(cells).ok());
}

TEST(SimplexCells, TwoTetsSharingAFaceFig4) {
  const SimplexCells cells = build_cells(two_tets());
  ASSERT_EQ(cells.size(), 2u);
  EXPECT_EQ(count_external_faces(cells), 6u);
  // Cell 0's face opposite vertex 3 (local 3 = global 3) is the shared one.
  uint32_t shared0 = 4, shared1 = 4;
  for (uint32_t k = 0; k < 4; ++k) {
    if (cells.neighbour[0][k] == 1u) shared0 = k;
    if (cells.neighbour[1][k] == 0u) shared1 = k;
  }
  ASSERT_LT(shared0, 4u);
  ASSERT_LT(shared1, 4u);
  EXPECT_EQ(cells.tet[0][shared0], 3u);
  EXPECT_EQ(cells.neighbour_face[0][shared0], shared1);
  EXPECT_EQ(cells.neighbour_face[1][shared1], shared0);
  // A boundary edge of the shared face has one external face in each cell: they link across cells;
  // an edge through the apex (vertex 3 or 4) joins two faces of the same cell.
  for (uint32_t c = 0; c < 2; ++c)
    for (uint32_t k = 0; k < 4; ++k) {
      if (cells.neighbour[c][k] != kNoSimplex) continue;
      for (uint32_t j = 0; j < 3; ++j) {
        const auto e = edge_of(cells, c, k, j);
        const bool on_shared = e.second <= 2;
        const uint32_t other = cells.boundary_link[c][3 * k + j];
        EXPECT_EQ(simplex_face_cell(other), on_shared ? 1 - c : c)
            << "cell " << c << " face " << k << " slot " << j;
      }
    }
  EXPECT_TRUE(check_boundary(cells).ok());
}

TEST(SimplexRemoval, ThreeExternalFacesFig5) {
  SimplexCells cells = build_cells(two_tets());
  const Removal r = remove_cell(cells, 1);
  ASSERT_TRUE(r.removed);
  EXPECT_EQ(r.kind, RemovalCase::ThreeExternal);
  EXPECT_EQ(r.alive_neighbours, 1);
  // The target face t0 (cell 0's former internal face) is attached to the sources s0..s2: cell
  // 0's three other faces, one per edge.
  uint32_t t0 = 4;
  for (uint32_t k = 0; k < 4; ++k)
    if (cells.tet[0][k] == 3u) t0 = k;
  ASSERT_LT(t0, 4u);
  std::set<uint32_t> sources;
  for (uint32_t j = 0; j < 3; ++j) sources.insert(cells.boundary_link[0][3 * t0 + j]);
  EXPECT_EQ(sources.size(), 3u);
  EXPECT_EQ(sources.count(simplex_face_id(0, t0)), 0u);
  EXPECT_TRUE(links_stay_in_cell(cells, 0));
  EXPECT_EQ(count_external_faces(cells), 4u);
  EXPECT_EQ(cells.alive_count, 1u);
  const BoundaryCheck check = check_boundary(cells);
  EXPECT_TRUE(check.ok()) << check.link_mismatches << " link mismatches";
}

TEST(SimplexRemoval, TwoExternalFacesFigs6And9) {
  // A cube of six tets about its diagonal (0, 7): each has two faces on the cube, two inside.
  SimplexCells cells = build_cells(kuhn_grid(1));
  ASSERT_EQ(cells.size(), 6u);
  for (uint32_t c = 0; c < 6; ++c) {
    uint32_t external = 0;
    for (uint32_t k = 0; k < 4; ++k) external += cells.neighbour[c][k] == kNoSimplex;
    EXPECT_EQ(external, 2u);
  }
  const Removal r = remove_cell(cells, 0);
  EXPECT_EQ(r.kind, RemovalCase::TwoExternal);
  EXPECT_EQ(r.alive_neighbours, 2);
  // Targets t0, t1: the neighbours' new faces. The fan about the diagonal was closed, so they are
  // attached to each other across it (the seed's "attach t0 to t1").
  std::vector<uint32_t> targets;
  for (uint32_t k = 0; k < 4; ++k)
    if (r.new_faces[k] != kNoSimplex) targets.push_back(r.new_faces[k]);
  ASSERT_EQ(targets.size(), 2u);
  bool linked = false;
  for (uint32_t j = 0; j < 3; ++j) linked |= cells.link(targets[0], j) == targets[1];
  EXPECT_TRUE(linked);
  EXPECT_EQ(count_external_faces(cells), 12u);  // two cube triangles gone, two new faces
  EXPECT_TRUE(check_boundary(cells).ok());
}

TEST(SimplexRemoval, OneExternalFaceFigs7And8) {
  SimplexCells cells = build_cells(cube_five());
  ASSERT_EQ(remove_cell(cells, 1).kind, RemovalCase::ThreeExternal);
  ASSERT_TRUE(check_boundary(cells).ok());
  // The central tet now has one external face f0 and three neighbours.
  const Removal r = remove_cell(cells, 0);
  EXPECT_EQ(r.kind, RemovalCase::OneExternal);
  EXPECT_EQ(r.alive_neighbours, 3);
  // Left: three corner tets touching only along face diagonals (non-manifold edges): by the rule
  // through the solid each keeps its own closed surface.
  for (uint32_t c : {2u, 3u, 4u}) EXPECT_TRUE(links_stay_in_cell(cells, c)) << c;
  EXPECT_EQ(count_external_faces(cells), 12u);
  EXPECT_TRUE(check_boundary(cells).ok());
}

TEST(SimplexRemoval, InteriorCellLeavesACavity) {
  // Cube of five: the central tet has no external face.
  SimplexCells cube = build_cells(cube_five());
  const Removal r = remove_cell(cube, 0);
  EXPECT_EQ(r.kind, RemovalCase::Interior);
  EXPECT_EQ(r.alive_neighbours, 4);
  for (uint32_t c = 1; c < 5; ++c) EXPECT_TRUE(links_stay_in_cell(cube, c)) << c;
  EXPECT_TRUE(check_boundary(cube).ok());

  // Deep inside the lens every fan about the removed cell's edges is closed: the four new faces
  // form a closed cavity, linked only to each other.
  SimplexCells lens =
      build_cells(eye::make_lens_tets(eye::default_eye_params(), eye::resolution_for_level(0)));
  uint32_t deep = kNoSimplex;
  for (uint32_t c = 0; c < lens.size() && deep == kNoSimplex; ++c) {
    bool ok = true;
    for (uint32_t k = 0; k < 4 && ok; ++k) {
      const uint32_t nb = lens.neighbour[c][k];
      ok = nb != kNoSimplex;
      for (uint32_t q = 0; q < 4 && ok; ++q) ok = lens.neighbour[nb][q] != kNoSimplex;
    }
    // Also no vertex of c on the lens surface: every external face is far away.
    if (ok && std::abs(lens.rest_z[c]) < 0.5f && std::hypot(lens.rest_x[c], lens.rest_y[c]) < 2.0f)
      deep = c;
  }
  ASSERT_NE(deep, kNoSimplex);
  const uint32_t faces_before = count_external_faces(lens);
  const Removal lr = remove_cell(lens, deep);
  EXPECT_EQ(lr.kind, RemovalCase::Interior);
  EXPECT_EQ(count_external_faces(lens), faces_before + 4);
  std::set<uint32_t> new_faces(lr.new_faces.begin(), lr.new_faces.end());
  ASSERT_EQ(new_faces.size(), 4u);
  for (uint32_t f : new_faces)
    for (uint32_t j = 0; j < 3; ++j) EXPECT_EQ(new_faces.count(lens.link(f, j)), 1u);
  EXPECT_TRUE(check_boundary(lens).ok());
}

TEST(SimplexRemoval, IsolatedCellJustDisappears) {
  SimplexCells cells = build_cells(one_tet());
  const Removal r = remove_cell(cells, 0);
  EXPECT_EQ(r.kind, RemovalCase::Isolated);
  EXPECT_EQ(r.alive_neighbours, 0);
  EXPECT_EQ(cells.alive_count, 0u);
  EXPECT_EQ(count_external_faces(cells), 0u);
  EXPECT_TRUE(check_boundary(cells).ok());
  const Removal again = remove_cell(cells, 0);
  EXPECT_FALSE(again.removed);
  EXPECT_FALSE(remove_cell(cells, 5).removed);
}

TEST(SimplexCells, CheckDetectsACorruptedLink) {
  SimplexCells cells = build_cells(kuhn_grid(1));
  ASSERT_TRUE(check_boundary(cells).ok());
  uint32_t k = 0;
  while (cells.neighbour[0][k] != kNoSimplex) ++k;
  std::swap(cells.boundary_link[0][3 * k], cells.boundary_link[0][3 * k + 1]);
  const BoundaryCheck check = check_boundary(cells);
  EXPECT_FALSE(check.ok());
  EXPECT_GE(check.link_mismatches, 2u);
  EXPECT_GE(check.asymmetric_links, 1u);
}

TEST(SimplexCells, BuildFlipsNegativeTetsAndRejectsAFaceSharedThrice) {
  TetMesh m = one_tet();
  std::swap(m.tets[0][2], m.tets[0][3]);
  const SimplexCells flipped = build_cells(m);
  EXPECT_GT(flipped.volume[0], 0.0f);
  EXPECT_TRUE(check_boundary(flipped).ok());

  TetMesh bad = two_tets();
  bad.vertices.push_back(Vec3(1, 1, 0.5));
  bad.tets.push_back({0, 1, 2, 5});
  EXPECT_THROW(build_cells(bad), std::invalid_argument);
}

}  // namespace
}  // namespace phaco::simplex

namespace phaco::simplex {
namespace {

// A crack (break_link) along the plane x = 2 of a 4×4×4 Kuhn grid gives exactly the cells built
// from the grid cut there (the plane's vertices duplicated for the tets beyond it): the same
// neighbours and the same boundary links, face for face; and two fragments.
TEST(SimplexCrack, BreakingTheLinksAcrossAPlaneEqualsBuildingTheTwoHalves) {
  const TetMesh grid = testing::kuhn_grid(4);
  auto beyond = [&](const std::array<uint32_t, 4>& t) {
    double x = 0;
    for (uint32_t v : t) x += grid.vertices[v].x();
    return x / 4 > 2.0;
  };
  TetMesh halves = grid;
  std::vector<uint32_t> twin(grid.vertices.size(), kNoSimplex);
  for (auto& t : halves.tets) {
    if (!beyond(t)) continue;
    for (uint32_t& v : t) {
      if (grid.vertices[v].x() != 2.0) continue;
      if (twin[v] == kNoSimplex) {
        twin[v] = static_cast<uint32_t>(halves.vertices.size());
        halves.vertices.push_back(grid.vertices[v]);
      }
      v = twin[v];
    }
  }
  const SimplexCells reference = build_cells(halves);
  SimplexCells cracked = build_cells(grid);
  const uint32_t faces_before = count_external_faces(cracked);
  uint32_t broken = 0;
  std::pair<uint32_t, uint32_t> first{kNoSimplex, 0};
  for (uint32_t c = 0; c < cracked.size(); ++c) {
    if (beyond(grid.tets[c])) continue;
    for (uint32_t k = 0; k < 4; ++k) {
      const uint32_t d = cracked.neighbour[c][k];
      if (d == kNoSimplex || !beyond(grid.tets[d])) continue;
      if (first.first == kNoSimplex) first = {c, k};
      broken += break_link(cracked, c, k);
    }
  }
  EXPECT_EQ(broken, 2u * 4u * 4u) << "two triangles per unit square of the plane";
  EXPECT_FALSE(break_link(cracked, first.first, first.second)) << "a link breaks once";
  EXPECT_EQ(count_external_faces(cracked), faces_before + 2 * broken);
  EXPECT_EQ(cracked.neighbour, reference.neighbour);
  EXPECT_EQ(cracked.boundary_link, reference.boundary_link);
  Fragments f;
  FragmentScratch scratch;
  label_fragments_painting(cracked, f, scratch);
  EXPECT_EQ(f.count, 2u);
}

}  // namespace
}  // namespace phaco::simplex
