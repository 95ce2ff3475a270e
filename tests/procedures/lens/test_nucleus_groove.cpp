// The nucleus_removal drill's start state (procedures/lens/nucleus_groove): the cross-shaped
// groove, measured by the phaco_sculpting drill's own trench measure (trench_measure.hpp, seed
// 000 §6.3), meets that drill's trench targets (data/drills/phaco_sculpting.json): two trenches
// 1.4–2.0 mm wide... here 1.5 tip diameters (1.35 mm) within a cell, 70–90 % of the nucleus deep,
// crossing at 90°. And removing the groove keeps the simplex boundary sound.
#include <gtest/gtest.h>

#include <cmath>

#include "procedures/eye/eye_mesh.hpp"
#include "procedures/lens/fragment_lens.hpp"
#include "procedures/lens/nucleus_groove.hpp"
#include "procedures/lens/trench_measure.hpp"

namespace phaco::lens {
namespace {

TEST(NucleusGroove, TheCrossMeetsTheSculptingDrillsTrenchTargets) {
  const TetMesh mesh = eye::make_lens_tets(eye::default_eye_params(), eye::resolution_for_level(1));
  const SimplexCells cells = simplex::build_cells(mesh);
  const CrossGroove g;  // the standard eye's nucleus, 1.35 mm wide, 80 % deep
  const std::vector<uint32_t> ids = groove_cells(cells, g);
  ASSERT_GT(ids.size(), 100u);
  std::vector<RemovedElement> removed;
  for (uint32_t c : ids) {
    const Vec3 p(cells.rest_x[c], cells.rest_y[c], cells.rest_z[c]);
    // One stroke per arm, as a sculptor's passes along each trench.
    const uint32_t stroke = std::abs(p.x()) >= std::abs(p.y()) ? 0 : 1;
    removed.push_back({p, cells.volume[c], stroke});
  }
  const NucleusShape n{g.nucleus_radius_mm, g.nucleus_anterior_mm, -g.nucleus_posterior_mm};
  const TrenchReport r = measure_trenches(removed, n);
  ASSERT_EQ(r.trenches.size(), 2u);
  const double cell = std::cbrt(r.volume_removed_mm3 / double(ids.size()));
  for (const Trench& t : r.trenches) {
    EXPECT_NEAR(t.width_mm, g.width_mm, cell) << "width";
    EXPECT_GE(t.depth_fraction, 0.7);
    EXPECT_LE(t.depth_fraction, 0.9);
  }
  EXPECT_NEAR(r.crossing_angle_deg, 90.0, 5.0);
}

TEST(NucleusGroove, RemovingItKeepsTheBoundarySoundAndTheLensOnePiece) {
  const TetMesh mesh = eye::make_lens_tets(eye::default_eye_params(), eye::resolution_for_level(0));
  FragmentLens l = make_fragment_lens(mesh, FragmentLensSettings{});
  const std::vector<uint32_t> ids = groove_cells(l.cells, CrossGroove{});
  FragmentLensStats st;
  remove_lens_cells(l, ids, st);
  EXPECT_EQ(l.cells_removed, ids.size());
  EXPECT_TRUE(simplex::check_boundary(l.cells).ok());
  // The floor (20 % of the nucleus and the posterior cortex) holds the quadrants together; crumbs
  // the slabs cut off are a few cells at most.
  uint32_t big = 0;
  for (uint32_t f = 0; f < l.fragments.count; ++f) big += l.fragments.size_of(f) > 20;
  EXPECT_EQ(big, 1u);
}

}  // namespace
}  // namespace phaco::lens
