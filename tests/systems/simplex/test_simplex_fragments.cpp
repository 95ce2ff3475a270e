// Fragments: painting and parallel union-find give the same table; the incremental update after
// removals equals a fresh labelling.
#include <gtest/gtest.h>
#include <oneapi/tbb/task_arena.h>

#include <random>

#include "procedures/eye/eye_mesh.hpp"
#include "procedures/eye/eye_params.hpp"
#include "procedures/eye/resolution.hpp"
#include "systems/simplex/simplex_cells.hpp"
#include "systems/simplex/simplex_fragments.hpp"
#include "tests/systems/simplex/simplex_meshes.hpp"

namespace phaco::simplex {
namespace {

void expect_same(const Fragments& a, const Fragments& b, const char* what) {
  EXPECT_EQ(a.count, b.count) << what;
  EXPECT_EQ(a.label, b.label) << what;
  EXPECT_EQ(a.offsets, b.offsets) << what;
  EXPECT_EQ(a.members, b.members) << what;
  EXPECT_EQ(a.mass, b.mass) << what;
  EXPECT_EQ(a.rest_cx, b.rest_cx) << what;
  EXPECT_EQ(a.rest_cy, b.rest_cy) << what;
  EXPECT_EQ(a.rest_cz, b.rest_cz) << what;
}

TEST(SimplexFragments, RemovingASlabSplitsTheGridInTwo) {
  // 3×3×3 cubes: removing the middle slab of cubes (1 < x < 2) leaves two fragments.
  TetMesh m = testing::kuhn_grid(3);
  SimplexCells cells = build_cells(m);
  FragmentScratch scratch;
  Fragments paint, uf;
  label_fragments_painting(cells, paint, scratch);
  EXPECT_EQ(paint.count, 1u);
  double total = 0;
  for (uint32_t c = 0; c < cells.size(); ++c) total += cells.mass[c];
  EXPECT_NEAR(paint.mass[0], total, 1e-12 * total);
  EXPECT_NEAR(paint.rest_cx[0], 1.5, 1e-6);
  // Remove the slab 1 ≤ x ≤ 2 (all tets whose centre lies there).
  for (uint32_t c = 0; c < cells.size(); ++c)
    if (cells.rest_x[c] > 1.0f && cells.rest_x[c] < 2.0f) remove_cell(cells, c);
  label_fragments_painting(cells, paint, scratch);
  label_fragments_union_find(cells, uf, scratch, 7);
  ASSERT_EQ(paint.count, 2u);
  expect_same(paint, uf, "painting vs union-find");
  EXPECT_NEAR(paint.rest_cx[0], 0.5, 1e-6);  // cell 0 is in the x < 1 slab
  EXPECT_NEAR(paint.rest_cx[1], 2.5, 1e-6);
  EXPECT_EQ(paint.size_of(0), paint.size_of(1));
  EXPECT_EQ(testing::brute_force_labels(cells), paint.label);
  for (uint32_t c = 0; c < cells.size(); ++c)
    if (!cells.alive[c]) {
      EXPECT_EQ(paint.label[c], kNoSimplex);
    }
}

TEST(SimplexFragments, UnionFindIsTheSameForOneTwoAndFourThreads) {
  SimplexCells cells =
      build_cells(eye::make_lens_tets(eye::default_eye_params(), eye::resolution_for_level(0)));
  std::mt19937 rng(5);
  const auto order = testing::random_order(cells.size(), rng);
  for (uint32_t i = 0; i < cells.size() * 6 / 10; ++i)
    remove_cell(cells, order[i]);  // many fragments
  FragmentScratch scratch;
  Fragments paint;
  label_fragments_painting(cells, paint, scratch);
  EXPECT_GT(paint.count, 50u);
  EXPECT_EQ(testing::brute_force_labels(cells), paint.label);
  for (int threads : {1, 2, 4}) {
    tbb::task_arena arena(threads);
    Fragments uf;
    FragmentScratch s;
    arena.execute([&] { label_fragments_union_find(cells, uf, s, 64); });
    expect_same(paint, uf, "union-find");
  }
}

TEST(SimplexFragments, UpdateRelabelsOnlyWhenARemovalCouldSplit) {
  SimplexCells cells = build_cells(testing::kuhn_grid(2));
  FragmentScratch scratch;
  Fragments frags, fresh;
  label_fragments_painting(cells, frags, scratch);
  // A corner tet of the grid: find one with a single neighbour, if any, else with the fewest.
  uint32_t lone = kNoSimplex, fewest = 5;
  for (uint32_t c = 0; c < cells.size(); ++c) {
    uint32_t nbs = 0;
    for (uint32_t k = 0; k < 4; ++k) nbs += cells.neighbour[c][k] != kNoSimplex;
    if (nbs < fewest) fewest = nbs, lone = c;
  }
  ASSERT_NE(lone, kNoSimplex);
  const Removal r = remove_cell(cells, lone);
  const FragmentUpdate u = update_fragments(cells, std::span<const Removal>(&r, 1), frags, scratch);
  EXPECT_EQ(u.relabelled, r.alive_neighbours >= 2);
  label_fragments_painting(cells, fresh, scratch);
  expect_same(fresh, frags, "after one removal");

  // Removing all but one cell's neighbours one by one: the last neighbour's removal leaves a lone
  // fragment; removing the lone cell (no neighbours) drops the fragment without relabelling.
  const uint32_t keep = cells.size() - 1;
  std::vector<Removal> batch;
  for (uint32_t k = 0; k < 4; ++k)
    if (cells.neighbour[keep][k] != kNoSimplex)
      batch.push_back(remove_cell(cells, cells.neighbour[keep][k]));
  update_fragments(cells, batch, frags, scratch);
  label_fragments_painting(cells, fresh, scratch);
  expect_same(fresh, frags, "after isolating a cell");
  const uint32_t before = frags.count;
  const Removal last = remove_cell(cells, keep);
  EXPECT_EQ(last.alive_neighbours, 0);
  const FragmentUpdate v =
      update_fragments(cells, std::span<const Removal>(&last, 1), frags, scratch);
  EXPECT_FALSE(v.relabelled);
  EXPECT_EQ(frags.count, before - 1);
  label_fragments_painting(cells, fresh, scratch);
  expect_same(fresh, frags, "after dropping the lone fragment");
}

TEST(SimplexFragments, ConfirmSplitKeepsOnlyRealSplits) {
  // Six tets in a closed fan about the cube's diagonal: removing one leaves a chain (its two
  // neighbours meet the other way round); removing a middle cell of that chain does split it.
  SimplexCells cells = build_cells(testing::kuhn_grid(1));
  FragmentScratch scratch;
  Fragments frags, fresh;
  label_fragments_painting(cells, frags, scratch);
  Removal first = remove_cell(cells, 0);
  ASSERT_TRUE(first.may_split);
  confirm_split(cells, first, scratch);
  EXPECT_FALSE(first.may_split);
  EXPECT_FALSE(
      update_fragments(cells, std::span<const Removal>(&first, 1), frags, scratch).relabelled);
  EXPECT_EQ(frags.count, 1u);
  // A chain cell with two alive neighbours.
  uint32_t middle = kNoSimplex;
  for (uint32_t c = 1; c < 6 && middle == kNoSimplex; ++c) {
    uint32_t nbs = 0;
    for (uint32_t k = 0; k < 4; ++k) nbs += cells.neighbour[c][k] != kNoSimplex;
    if (nbs == 2) middle = c;
  }
  ASSERT_NE(middle, kNoSimplex);
  Removal second = remove_cell(cells, middle);
  confirm_split(cells, second, scratch);
  EXPECT_TRUE(second.may_split);
  EXPECT_TRUE(
      update_fragments(cells, std::span<const Removal>(&second, 1), frags, scratch).relabelled);
  EXPECT_EQ(frags.count, 2u);
  label_fragments_painting(cells, fresh, scratch);
  expect_same(fresh, frags, "after the split");
}

}  // namespace
}  // namespace phaco::simplex
