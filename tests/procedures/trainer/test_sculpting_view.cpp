// Sculpting a trainee can see (issue 19 item 4): the real sculpting scene's lens, sculpted as the
// probe would (its tets removed along a trench) or cracked into fragments, through fill_snapshot
// and the renderer into an off-screen framebuffer under Mesa, checked on pixels: the red reflex
// through a trench brightens as the nucleus beneath thins (brighter and redder than the intact
// nucleus, more after the deep passes than after the shallow ones), and fragments show apart. Needs
// an X display (ctest runs this under xvfb-run).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <set>

#include "components/tet_topology.hpp"
#include "engine/core/clock.hpp"
#include "engine/render/lens_thickness.hpp"
#include "engine/render/offscreen.hpp"
#include "engine/render/renderer.hpp"
#include "procedures/scene/lens_fragments.hpp"
#include "procedures/scene/lens_sculpting.hpp"
#include "procedures/trainer/snapshot_fill.hpp"
#include "tests/support/environment.hpp"
#include "tests/support/gl_window.hpp"
#include "tests/support/scene_run.hpp"

namespace phaco {
namespace {

constexpr int kW = 480, kH = 360;
// The trench: along x through the centre, as the expert's first (DESIGN.md §6: 1.4-2.0 wide).
constexpr double kTrenchHalfWidth = 0.75, kTrenchArm = 2.4;
// Its floor after the expert's shallow passes (tip at z 0.3, radius 0.45) and after the deep ones
// (tip at z -0.86): 2.6 and 1.4 mm of lens left above the posterior pole (z -2.7).
constexpr double kShallowFloorZ = -0.15, kDeepFloorZ = -1.3;

struct Colour {
  double r = 0, g = 0, b = 0;
  double brightness() const { return r + g + b; }
  double redness() const { return r - 0.5 * (g + b); }
};

class SculptingView : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { window_ = test::make_hidden_gl_window("test_sculpting_view"); }
  static void TearDownTestSuite() { test::close_gl_window(window_); }
  void SetUp() override {
    PHACO_REQUIRE_GL_WINDOW(window_);
    target_ = std::make_unique<render::OffscreenTarget>(kW, kH);
    render::RenderOptions o;
    o.guidance = false;  // the trench cue would lie on the trench
    renderer_ = std::make_unique<render::Renderer>(o);
  }

  static std::unique_ptr<Scene> sculpting_scene(const char* lens_model) {
    Scenario s = test::repo_scenario("phaco_sculpting_expert.json");
    s.eye.level = 3;  // the expert's, as the trainer shows it
    s.methods["lens.model"] = lens_model;
    SceneOptions o;
    o.cache_dir = test::scene_cache_dir();
    auto scene = build_scene(s, o);
    step(*scene);
    return scene;
  }

  // The scene as the microscope shows it, instruments left out (the probe's shaft would cross
  // the lens). Kept for a look under $PHACO_TEST_SHOTS/<name>.png (and <name>_zoomed.png) when
  // that is set.
  std::vector<uint8_t> view(Scene& scene, const char* name) {
    render::RenderSnapshot snap;
    fill_snapshot(scene, snap);
    snap.tools.clear();
    target_->bind();
    if (const char* dir = std::getenv("PHACO_TEST_SHOTS")) {
      render::Microscope zoomed;
      zoomed.field_mm = 7;
      renderer_->draw(snap, zoomed, kW, kH);
      render::save_screenshot(std::string(dir) + "/" + name + "_zoomed.png", kW, kH);
      renderer_->draw(snap, {}, kW, kH);
      render::save_screenshot(std::string(dir) + "/" + name + ".png", kW, kH);
    }
    renderer_->draw(snap, {}, kW, kH);
    return render::read_pixels(kW, kH);
  }

  // Mean colour over the disc of radius r_mm about the eye-frame point p (0..255 per channel).
  static Colour mean(const std::vector<uint8_t>& rgb, const Vec3& p, double r_mm) {
    const auto c = render::project_to_pixel({}, p, kW, kH);
    const double r = r_mm * std::min(kW, kH) / render::Microscope{}.field_mm;
    Colour m;
    int n = 0;
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < kW; ++x) {
        if (std::hypot(x + 0.5 - c[0], y + 0.5 - c[1]) > r) continue;
        const uint8_t* q = &rgb[(static_cast<size_t>(y) * kW + x) * 3];
        m.r += q[0], m.g += q[1], m.b += q[2];
        ++n;
      }
    if (n > 0) m.r /= n, m.g /= n, m.b /= n;
    return m;
  }

  static GLFWwindow* window_;
  std::unique_ptr<render::OffscreenTarget> target_;
  std::unique_ptr<render::Renderer> renderer_;
};
GLFWwindow* SculptingView::window_ = nullptr;

// Removes the tets whose centre lies in the trench above floor_z (what the probe's passes do).
void sculpt_trench(LensSculpting& ls, double floor_z) {
  TetTopology& topo = ls.topology;
  for (uint32_t t = 0; t < topo.tet_count; ++t)
    if (topo.alive[t] && std::abs(topo.centre_y[t]) < kTrenchHalfWidth &&
        std::abs(topo.centre_x[t]) < kTrenchArm && topo.centre_z[t] > floor_z)
      remove_tet(topo, t);
}

void print(const char* what, const Colour& c) {
  std::printf("%-28s rgb %5.1f %5.1f %5.1f  brightness %5.1f  redness %5.1f\n", what, c.r, c.g, c.b,
              c.brightness(), c.redness());
}

TEST_F(SculptingView, TrenchGlowsRedderAndBrighterAsTheNucleusBeneathThins) {
  auto scene = sculpting_scene("tets");
  LensSculpting& ls = scene->world.at<LensSculpting>(*scene->body(BodyPart::Lens));
  // Where to look: the trench's floor either side of the centre, seen before sculpting (the
  // intact nucleus there), after the shallow passes and after the deep ones; the same pixels each
  // time, so the capsule's sheen and the illuminator's reflection on it are alike in all three.
  // The nucleus beside the trench, inside the pupil, is the check that only the trench changed.
  const std::array floor = {Vec3(-1.2, 0, 1.6), Vec3(1.2, 0, 1.6)};
  const std::array beside = {Vec3(-1.2, -1.7, 1.6), Vec3(1.2, -1.7, 1.6)};
  auto average = [&](const std::vector<uint8_t>& img, const auto& points) {
    Colour sum;
    for (const Vec3& p : points) {
      const Colour c = mean(img, p, 0.3);
      sum.r += c.r / points.size(), sum.g += c.g / points.size(), sum.b += c.b / points.size();
    }
    return sum;
  };

  const auto intact_img = view(*scene, "sculpting_intact");
  sculpt_trench(ls, kShallowFloorZ);
  const auto shallow_img = view(*scene, "sculpting_shallow");
  sculpt_trench(ls, kDeepFloorZ);
  const auto deep_img = view(*scene, "sculpting_deep");
  const Colour intact = average(intact_img, floor);
  const Colour shallow = average(shallow_img, floor);
  const Colour deep = average(deep_img, floor);
  print("intact nucleus", intact);
  print("shallow trench floor", shallow);
  print("deep trench floor", deep);

  // The floor: brighter and redder than the intact nucleus, and more so once deep.
  EXPECT_GT(shallow.brightness(), intact.brightness() + 10);
  EXPECT_GT(shallow.redness(), intact.redness() + 10);
  EXPECT_GT(deep.brightness(), shallow.brightness() + 10);
  EXPECT_GT(deep.redness(), shallow.redness() + 10);
  // Beside the trench nothing changed.
  EXPECT_NEAR(average(deep_img, beside).brightness(), average(intact_img, beside).brightness(), 6);

  {
    // A figure for the report, not an assertion: the map's rebuild when the lens changed.
    render::RenderSnapshot snap;
    fill_snapshot(*scene, snap);
    std::vector<const render::BodyView*> lens;
    size_t triangles = 0;
    for (const auto& b : snap.bodies)
      if (b.look == render::Look::LensSurface || b.look == render::Look::LensInterior)
        lens.push_back(&b), triangles += b.tris.size() / 3;
    render::ThicknessMap map;
    Stopwatch clock;
    for (int i = 0; i < 20; ++i) render::build_thickness_map(lens, 128, map);
    std::printf("thickness map, 128^2 cells, %zu triangles (level %d): %.2f ms\n", triangles,
                scene->scenario.eye.level, clock.elapsed_ms() / 20);
  }
  // (The walls' shading is checked on exact geometry in tests/engine/render: the tets' jagged
  // rims make this trench's two walls unlike in more than their light.)
}

TEST_F(SculptingView, FragmentsShowApartWithTheReflexThroughTheCrack) {
  auto scene = sculpting_scene("fragments");
  LensFragments& lf = scene->world.at<LensFragments>(*scene->body(BodyPart::Lens));
  const auto before = view(*scene, "fragments_whole");
  // A crack through the whole lens along y (as a chop would make): two pieces.
  std::vector<uint32_t> crack;
  const SimplexCells& cells = lf.lens.cells;
  for (uint32_t i = 0; i < cells.size(); ++i)
    if (cells.alive[i] && std::abs(cells.x[i]) < 0.3) crack.push_back(i);
  lens::FragmentLensStats stats;
  lens::remove_lens_cells(lf.lens, crack, stats);
  ASSERT_GE(lf.lens.fragments.count, 2u);

  render::RenderSnapshot snap;
  fill_snapshot(*scene, snap);
  std::set<uint8_t> pieces;
  for (const auto& b : snap.bodies) pieces.insert(b.piece.begin(), b.piece.end());
  EXPECT_GE(pieces.size(), 2u) << "each vertex carries its fragment";

  const auto after = view(*scene, "fragments_cracked");
  const double top = 1.6;
  const Colour gap = mean(after, Vec3(0, -1.2, top), 0.12);
  const Colour left = mean(after, Vec3(-1.5, -1.2, top), 0.3);
  const Colour right = mean(after, Vec3(1.5, -1.2, top), 0.3);
  const Colour gap_before = mean(before, Vec3(0, -1.2, top), 0.12);
  print("crack site, whole lens", gap_before);
  print("crack", gap);
  print("left piece", left);
  print("right piece", right);
  // The fundus's reflex through the crack, brighter and redder than the pieces on either side and
  // than the lens there before.
  for (const Colour* piece : {&left, &right, &gap_before}) {
    EXPECT_GT(gap.brightness(), piece->brightness() + 30);
    EXPECT_GT(gap.redness(), piece->redness() + 30);
  }
  // The two pieces, alike in thickness and light, are tinted apart.
  EXPECT_GT(std::abs(left.brightness() - right.brightness()), 12);
}

}  // namespace
}  // namespace phaco
