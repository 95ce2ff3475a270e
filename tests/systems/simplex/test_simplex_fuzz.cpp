// Fuzz: random removal sequences. After every removal the incrementally maintained boundary equals
// the one rebuilt from scratch, and the fragment labels from painting, from union-find, from the
// incremental update and from a brute-force flood fill are the same. Removing everything leaves
// nothing.
#include <gtest/gtest.h>

#include <random>

#include "procedures/eye/eye_mesh.hpp"
#include "procedures/eye/eye_params.hpp"
#include "procedures/eye/resolution.hpp"
#include "systems/simplex/simplex_cells.hpp"
#include "systems/simplex/simplex_fragments.hpp"
#include "systems/simplex/simplex_surface.hpp"
#include "tests/systems/simplex/simplex_meshes.hpp"

namespace phaco::simplex {
namespace {

struct FuzzCounts {
  uint32_t removals = 0, checks = 0, relabels = 0;
  uint32_t by_case[5] = {0, 0, 0, 0, 0};
  uint32_t max_fragments = 0;
};

// Removes every cell in `order`, checking after each removal whose index passes `check_every`.
// Stops at the first failure (returns false).
bool run_sequence(const SimplexCells& initial, const std::vector<uint32_t>& order,
                  uint32_t check_dense, uint32_t check_every, FuzzCounts& counts,
                  uint32_t small_budget = 4) {
  SimplexCells cells = initial;
  FragmentScratch scratch;
  Fragments incremental, paint, uf;
  label_fragments_painting(cells, incremental, scratch);
  for (uint32_t i = 0; i < order.size(); ++i) {
    Removal r = remove_cell(cells, order[i]);
    if (!r.removed) continue;
    confirm_split(cells, r, scratch,
                  (i & 1) ? 256 : small_budget);  // a small budget: more relabels
    ++counts.removals;
    ++counts.by_case[static_cast<int>(r.kind)];
    counts.relabels +=
        update_fragments(cells, std::span<const Removal>(&r, 1), incremental, scratch).relabelled;
    if (i >= check_dense && (i + 1) % check_every != 0 && i + 1 != order.size()) continue;
    ++counts.checks;
    const BoundaryCheck check = check_boundary(cells);
    EXPECT_TRUE(check.ok()) << "removal " << i << " of cell " << order[i] << ": "
                            << check.neighbour_mismatches << " neighbour, " << check.link_mismatches
                            << " link, " << check.asymmetric_links << " asymmetric, "
                            << check.stale_entries << " stale";
    label_fragments_painting(cells, paint, scratch);
    label_fragments_union_find(cells, uf, scratch, 16);
    EXPECT_EQ(paint.label, uf.label) << "removal " << i;
    EXPECT_EQ(paint.members, uf.members) << "removal " << i;
    EXPECT_EQ(paint.label, incremental.label) << "removal " << i;
    EXPECT_EQ(paint.offsets, incremental.offsets) << "removal " << i;
    EXPECT_EQ(paint.mass, incremental.mass) << "removal " << i;
    EXPECT_EQ(paint.rest_cx, incremental.rest_cx) << "removal " << i;
    EXPECT_EQ(paint.rest_cy, incremental.rest_cy) << "removal " << i;
    EXPECT_EQ(paint.rest_cz, incremental.rest_cz) << "removal " << i;
    EXPECT_EQ(paint.members, incremental.members) << "removal " << i;
    EXPECT_EQ(paint.count, incremental.count) << "removal " << i;
    EXPECT_EQ(testing::brute_force_labels(cells), paint.label) << "removal " << i;
    counts.max_fragments = std::max(counts.max_fragments, paint.count);
    if (::testing::Test::HasFailure()) return false;
  }
  EXPECT_EQ(cells.alive_count, 0u);
  EXPECT_EQ(count_external_faces(cells), 0u);
  EXPECT_EQ(incremental.count, 0u);
  BoundarySurface surface;
  build_boundary_surface(cells, surface);
  EXPECT_TRUE(surface.triangles.empty());
  return !::testing::Test::HasFailure();
}

// Erosion as a tool would do it: each step removes a random cell among those with an external
// face (the current surface), so the sequence keeps cavities rare and non-manifold edges common.
std::vector<uint32_t> erosion_order(const SimplexCells& initial, std::mt19937& rng) {
  SimplexCells cells = initial;
  std::vector<uint32_t> order, surface;
  while (cells.alive_count > 0) {
    surface.clear();
    for (uint32_t c = 0; c < cells.size(); ++c)
      if (cells.alive[c])
        for (uint32_t k = 0; k < 4; ++k)
          if (cells.neighbour[c][k] == kNoSimplex) {
            surface.push_back(c);
            break;
          }
    // A batch of a few surface cells per scan keeps the order generation cheap.
    for (uint32_t b = 0; b < 8 && !surface.empty(); ++b) {
      const uint32_t pick = rng() % surface.size();
      const uint32_t c = surface[pick];
      surface[pick] = surface.back();
      surface.pop_back();
      if (remove_cell(cells, c).removed) order.push_back(c);
    }
  }
  return order;
}

TEST(SimplexFuzz, SmallGridsRandomOrders) {
  FuzzCounts counts;
  std::mt19937 rng(2026);
  const SimplexCells five = build_cells(testing::cube_five());
  const SimplexCells six = build_cells(testing::kuhn_grid(1));
  const SimplexCells grid2 = build_cells(testing::kuhn_grid(2));
  for (int s = 0; s < 1000; ++s)
    ASSERT_TRUE(run_sequence(five, testing::random_order(five.size(), rng), 99, 1, counts));
  for (int s = 0; s < 1000; ++s)
    ASSERT_TRUE(run_sequence(six, testing::random_order(six.size(), rng), 99, 1, counts));
  for (int s = 0; s < 400; ++s)
    ASSERT_TRUE(run_sequence(grid2, testing::random_order(grid2.size(), rng), 999, 1, counts));
  for (int s = 0; s < 100; ++s)
    ASSERT_TRUE(run_sequence(grid2, erosion_order(grid2, rng), 999, 1, counts));
  // Every case of the removal primitive was exercised, and splits happened.
  for (int k = 0; k < 5; ++k) EXPECT_GT(counts.by_case[k], 0u) << "case " << k;
  EXPECT_GT(counts.relabels, 0u);
  EXPECT_GT(counts.max_fragments, 3u);
}

TEST(SimplexFuzz, Grid3RandomAndErosionOrders) {
  FuzzCounts counts;
  std::mt19937 rng(77);
  const SimplexCells grid3 = build_cells(testing::kuhn_grid(3));
  for (int s = 0; s < 15; ++s)
    ASSERT_TRUE(run_sequence(grid3, testing::random_order(grid3.size(), rng), 999, 1, counts));
  for (int s = 0; s < 15; ++s)
    ASSERT_TRUE(run_sequence(grid3, erosion_order(grid3, rng), 999, 1, counts));
  for (int k = 0; k < 5; ++k) EXPECT_GT(counts.by_case[k], 0u) << "case " << k;
}

TEST(SimplexFuzz, LensLevel0RandomAndErosionOrders) {
  const SimplexCells lens =
      build_cells(eye::make_lens_tets(eye::default_eye_params(), eye::resolution_for_level(0)));
  ASSERT_TRUE(check_boundary(lens).ok());
  FuzzCounts counts;
  std::mt19937 rng(9);
  // Dense checks for the first removals, then every 331st, and at the end.
  ASSERT_TRUE(run_sequence(lens, testing::random_order(lens.size(), rng), 40, 331, counts, 256));
  ASSERT_TRUE(run_sequence(lens, erosion_order(lens, rng), 40, 331, counts, 256));
  for (int k = 0; k < 5; ++k) EXPECT_GT(counts.by_case[k], 0u) << "case " << k;
  EXPECT_GT(counts.max_fragments, 100u);
}

}  // namespace
}  // namespace phaco::simplex
