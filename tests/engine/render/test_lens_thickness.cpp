// The lens's thickness map (engine/render/lens_thickness): the solid length on each vertical line
// through a closed, outward-wound surface, checked against exact geometry (boxes, the eye's lens).
// CPU only: no display needed.
#include <gtest/gtest.h>

#include <cmath>

#include "engine/render/lens_thickness.hpp"
#include "procedures/eye/eye_geometry.hpp"
#include "procedures/eye/eye_mesh.hpp"
#include "tests/support/box_body.hpp"

namespace phaco::render {
namespace {

using test::add_box;

TEST(LensThickness, BoxIsItsHeightInsideAndZeroOutside) {
  BodyView b;
  add_box(b, Vec3(-2, -2, -0.5), Vec3(2, 2, 1.5));
  const BodyView* bodies[] = {&b};
  ThicknessMap map;
  // 64 cells: centres fall on the box's diagonals, where its faces' triangles meet (the top-left
  // rule counts such a line once).
  build_thickness_map(bodies, 64, map);
  ASSERT_EQ(map.size, 64);
  for (float y : {-1.9f, -0.7f, 0.0f, 0.3f, 1.9f})
    for (float x : {-1.9f, 0.0f, 0.45f, 1.9f}) EXPECT_NEAR(thickness_at(map, x, y), 2.0f, 1e-4f);
  EXPECT_EQ(thickness_at(map, 2.3f, 0), 0.0f);
  EXPECT_EQ(thickness_at(map, 0, -9), 0.0f);
  for (size_t i = 0; i < map.mm.size(); ++i) {
    const float v = map.mm[i];
    ASSERT_TRUE(v == 0.0f || std::abs(v - 2.0f) < 1e-4f) << "cell " << i << ": " << v;
    if (v > 0) {
      EXPECT_NEAR(map.top_z[i], 1.5f, 1e-5f);
    }
  }
}

TEST(LensThickness, StackedPiecesAddUpAndAGapIsNotCounted) {
  // Two boxes one above the other (a fragment lifted off the one beneath): the line through both
  // crosses 0.8 + 0.5 mm of solid, not the 2 mm from the top to the bottom.
  BodyView b;
  add_box(b, Vec3(-1, -1, -1.0), Vec3(1, 1, -0.2));
  add_box(b, Vec3(-0.5, -0.5, 0.5), Vec3(0.5, 0.5, 1.0));
  const BodyView* bodies[] = {&b};
  ThicknessMap map;
  build_thickness_map(bodies, 48, map);
  EXPECT_NEAR(thickness_at(map, 0.1f, -0.2f), 1.3f, 1e-4f);
  EXPECT_NEAR(thickness_at(map, 0.8f, 0.8f), 0.8f, 1e-4f);
}

TEST(LensThickness, TheEyesLensIsItsAxialThicknessOnTheAxis) {
  const eye::EyeParams params = eye::default_eye_params();
  const eye::EyeGeometry g = eye::eye_geometry(params);
  const SurfaceMesh m = eye::make_lens_surface(params, eye::resolution_for_level(2));
  BodyView b;
  for (const Vec3& v : m.vertices)
    for (int c = 0; c < 3; ++c) b.xyz.push_back(static_cast<float>(v[c]));
  for (const auto& t : m.triangles) b.tris.insert(b.tris.end(), t.begin(), t.end());
  const BodyView* bodies[] = {&b};
  ThicknessMap map;
  build_thickness_map(bodies, 128, map);
  const double a = g.lens_a;
  const double axial = g.lens_c_anterior + g.lens_c_posterior;
  for (double r : {0.0, 1.5, 3.0, 3.75}) {
    const double exact = axial * std::sqrt(1 - r * r / (a * a));
    // The mesh's facets lie inside the ellipsoid: a few percent thinner at most.
    EXPECT_NEAR(thickness_at(map, static_cast<float>(r), 0), exact, 0.04 * axial) << "r " << r;
  }
  EXPECT_EQ(thickness_at(map, static_cast<float>(a + 0.3), 0), 0.0f);
}

}  // namespace
}  // namespace phaco::render
