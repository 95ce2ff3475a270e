// The microscope view's pixels (engine/render, issue 8 item 1): synthetic snapshots built from the
// real eye meshes (level 1), drawn with Mesa into an off-screen framebuffer, checked pixel by
// pixel. Needs an X display (ctest runs this under xvfb-run); skips without one.
#include <GLFW/glfw3.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <opencv2/imgcodecs.hpp>

#include "engine/render/offscreen.hpp"
#include "engine/render/renderer.hpp"
#include "procedures/eye/eye_geometry.hpp"
#include "procedures/eye/eye_mesh.hpp"
#include "tests/support/box_body.hpp"
#include "tests/support/environment.hpp"
#include "tests/support/gl_window.hpp"

namespace phaco::render {
namespace {

constexpr int kW = 480, kH = 360;
constexpr double kPi = 3.14159265358979323846;

struct Image {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;
  const uint8_t* at(int x, int y) const { return &rgb[(static_cast<size_t>(y) * width + x) * 3]; }
  // Pixels in the disc (cx, cy, r) satisfying pred, as a fraction of the disc's pixels.
  double fraction(double cx, double cy, double r, const std::function<bool(const uint8_t*)>& pred,
                  double r_inner = 0) const {
    int n = 0, hit = 0;
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x) {
        const double d = std::hypot(x + 0.5 - cx, y + 0.5 - cy);
        if (d > r || d < r_inner) continue;
        ++n;
        hit += pred(at(x, y)) ? 1 : 0;
      }
    return n ? static_cast<double>(hit) / n : 0;
  }
  int count(double cx, double cy, double r, const std::function<bool(const uint8_t*)>& pred) const {
    int hit = 0;
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x)
        if (std::hypot(x + 0.5 - cx, y + 0.5 - cy) <= r && pred(at(x, y))) ++hit;
    return hit;
  }
};

bool red_reflex(const uint8_t* p) {
  return p[0] > 120 && p[0] > p[1] + 60 && p[0] > p[2] + 60;
}
bool background(const uint8_t* p) {
  return p[0] < 20 && p[1] < 20 && p[2] < 20;
}
// Blue-grey steel: no tissue of the brown-iris eye has blue above red.
bool steel(const uint8_t* p) {
  return p[2] > p[0] + 12 && p[2] > 50;
}
bool guidance_green(const uint8_t* p) {
  return p[1] > p[0] + 60 && p[1] > p[2] + 60;
}
double redness(const uint8_t* p) {
  return p[0] - 0.5 * (p[1] + p[2]);
}

BodyView body(const char* name, Look look, const SurfaceMesh& m) {
  BodyView b;
  b.name = name;
  b.look = look;
  for (const Vec3& v : m.vertices)
    for (int c = 0; c < 3; ++c) b.xyz.push_back(static_cast<float>(v[c]));
  for (const auto& t : m.triangles) b.tris.insert(b.tris.end(), t.begin(), t.end());
  b.topology_version = 1;
  return b;
}

// Edges used by exactly one triangle: the capsule's rim and any cut.
std::vector<uint32_t> open_edges(const std::vector<uint32_t>& tris) {
  std::map<std::pair<uint32_t, uint32_t>, int> uses;
  for (size_t t = 0; t < tris.size(); t += 3)
    for (int k = 0; k < 3; ++k) {
      uint32_t a = tris[t + k], b = tris[t + (k + 1) % 3];
      ++uses[{std::min(a, b), std::max(a, b)}];
    }
  std::vector<uint32_t> edges;
  for (const auto& [e, n] : uses)
    if (n == 1) edges.insert(edges.end(), {e.first, e.second});
  return edges;
}

class RendererTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    window_ = test::make_hidden_gl_window("test_renderer");
    if (!window_) return;
    const eye::EyeParams params = eye::default_eye_params();
    const eye::Resolution res = eye::resolution_for_level(1);
    geometry_ = new eye::EyeGeometry(eye::eye_geometry(params));
    RenderSnapshot* s = new RenderSnapshot;
    s->bodies.push_back(body("globe", Look::Sclera, eye::make_globe(params, res)));
    s->bodies.push_back(body("iris", Look::Iris, eye::make_iris(params, res)));
    s->bodies.push_back(body("lens", Look::LensSurface, eye::make_lens_surface(params, res)));
    s->bodies.push_back(body("capsule", Look::Capsule,
                             eye::make_capsule(params, res, eye::CapsuleLayout::Curvilinear)));
    s->bodies.back().edges = open_edges(s->bodies.back().tris);
    s->bodies.push_back(body("cornea", Look::Cornea, eye::make_cornea(params, res)));
    eye_ = s;
  }
  static void TearDownTestSuite() {
    delete eye_;
    delete geometry_;
    eye_ = nullptr;
    test::close_gl_window(window_);
  }
  void SetUp() override {
    PHACO_REQUIRE_GL_WINDOW(window_);
    target_ = std::make_unique<OffscreenTarget>(kW, kH);
  }

  Image render(Renderer& r, const RenderSnapshot& s, const Microscope& m = {}) {
    target_->bind();
    r.draw(s, m, kW, kH);
    return {kW, kH, read_pixels(kW, kH)};
  }
  static RenderOptions plain() {
    RenderOptions o;
    o.guidance = false;
    return o;
  }
  std::array<double, 2> px(const Vec3& p, const Microscope& m = {}) {
    return project_to_pixel(m, p, kW, kH);
  }
  double px_per_mm(const Microscope& m = {}) { return std::min(kW, kH) / m.field_mm; }

  static GLFWwindow* window_;
  static RenderSnapshot* eye_;
  static eye::EyeGeometry* geometry_;
  std::unique_ptr<OffscreenTarget> target_;
};
GLFWwindow* RendererTest::window_ = nullptr;
RenderSnapshot* RendererTest::eye_ = nullptr;
eye::EyeGeometry* RendererTest::geometry_ = nullptr;

TEST_F(RendererTest, EyeFillsTheFrameCentre) {
  Renderer r(plain());
  const Image img = render(r, *eye_);
  const auto c = px(Vec3::Zero());
  EXPECT_NEAR(c[0], kW / 2.0, 1.0);
  EXPECT_NEAR(c[1], kH / 2.0, 1.0);
  // The central 80 % of the short side is eye (no background colour).
  const double filled =
      img.fraction(c[0], c[1], 0.4 * kH, [](const uint8_t* p) { return !background(p); });
  EXPECT_GT(filled, 0.99);
  // The frame's corners lie beyond the globe (radius 12 mm, field 16 mm on 360 px): background.
  EXPECT_TRUE(background(img.at(2, 2)));
  EXPECT_TRUE(background(img.at(kW - 3, kH - 3)));
}

TEST_F(RendererTest, RedReflexFillsThePupilAndNotTheIris) {
  Renderer r(plain());
  const Image img = render(r, *eye_);
  const auto c = px(Vec3::Zero());
  const double pupil_px = geometry_->pupil_radius * px_per_mm();
  const double iris_px = geometry_->iris_outer_radius * px_per_mm();
  const double in_pupil = img.fraction(c[0], c[1], 0.85 * pupil_px, red_reflex);
  const double on_iris = img.fraction(c[0], c[1], 0.9 * iris_px, red_reflex, 1.15 * pupil_px);
  EXPECT_GT(in_pupil, 0.8);  // less the illuminator's reflection
  EXPECT_LT(on_iris, 0.05);
  // Brighter toward the centre (lit from behind through the lens's thickest part).
  EXPECT_GT(img.at(static_cast<int>(c[0]), static_cast<int>(c[1]))[0],
            img.at(static_cast<int>(c[0] + 0.8 * pupil_px), static_cast<int>(c[1]))[0]);
}

TEST_F(RendererTest, ACataractDimsTheReflexByTheLensThicknessOnTheLine) {
  // A cataract's lens (reflex_attenuation_per_mm > 0) passes less of the fundus's light the
  // thicker it is where one looks: the same lens made thinner glows brighter and redder; a clear
  // lens (0, the default) keeps the full reflex. Sculpting relies on it (issue 19 item 4).
  Renderer r(plain());
  const auto c = px(Vec3::Zero());
  const int x = static_cast<int>(c[0]), y = static_cast<int>(c[1] + 0.8 * px_per_mm());
  auto centre = [&](const RenderSnapshot& s) {
    const Image img = render(r, s);
    const uint8_t* p = img.at(x, y);  // below the illuminator's reflection
    return std::array<uint8_t, 3>{p[0], p[1], p[2]};
  };
  auto without_capsule = [&](double attenuation, float z_scale) {
    RenderSnapshot s = *eye_;
    std::erase_if(s.bodies, [](const BodyView& b) { return b.look == Look::Capsule; });
    for (BodyView& b : s.bodies)
      if (b.look == Look::LensSurface) {
        b.reflex_attenuation_per_mm = static_cast<float>(attenuation);
        for (size_t i = 2; i < b.xyz.size(); i += 3) b.xyz[i] *= z_scale;
      }
    return s;
  };
  auto brightness = [](const std::array<uint8_t, 3>& p) { return p[0] + p[1] + p[2]; };
  auto red = [](const std::array<uint8_t, 3>& p) { return redness(p.data()); };
  const auto clear = centre(without_capsule(0, 1));
  const auto cataract = centre(without_capsule(0.35, 1));
  const auto thinned = centre(without_capsule(0.35, 0.4f));
  EXPECT_TRUE(red_reflex(clear.data()));
  EXPECT_FALSE(red_reflex(cataract.data()));
  EXPECT_LT(red(cataract), red(clear) - 40);
  EXPECT_GT(red(thinned), red(cataract) + 30);
  EXPECT_GT(brightness(thinned), brightness(cataract) + 20);
}

TEST_F(RendererTest, AGroovesWallsAreShadedAndItsFloorGlows) {
  // A sculpted nucleus as exact geometry: a slab and two blocks either side of a straight groove
  // along x, 1.5 mm wide and 2 mm deep (DESIGN.md §6's trench), seen zoomed in without the
  // membranes. The illuminator is tilted toward 12 o'clock (+y): the groove's wall facing it (on
  // its 6 o'clock side) reads lighter than the wall facing away, all else being symmetric; the
  // floor, with less lens under it, glows brighter and redder than the top beside.
  Renderer r(plain());
  RenderSnapshot s = *eye_;
  std::erase_if(s.bodies, [](const BodyView& b) {
    return b.look == Look::LensSurface || b.look == Look::Capsule || b.look == Look::Cornea;
  });
  BodyView nucleus;
  nucleus.name = "lens.interior";
  nucleus.look = Look::LensInterior;
  nucleus.reflex_attenuation_per_mm = 0.4f;
  nucleus.topology_version = 1;
  test::add_box(nucleus, Vec3(-3, -3, -2.5), Vec3(3, 3, -0.5));
  test::add_box(nucleus, Vec3(-3, -3, -0.5), Vec3(3, -0.75, 1.5));
  test::add_box(nucleus, Vec3(-3, 0.75, -0.5), Vec3(3, 3, 1.5));
  s.bodies.push_back(nucleus);
  Microscope m;
  m.field_mm = 6;
  const Image img = render(r, s, m);
  // Mean brightness and redness over x in [-2, 2] and y in [y0, y1] at height z.
  auto strip = [&](double y0, double y1, double z) {
    const auto a = px(Vec3(-2, y1, z), m), b = px(Vec3(2, y0, z), m);
    double bright = 0, red = 0;
    int n = 0;
    for (int y = static_cast<int>(a[1]); y <= static_cast<int>(b[1]); ++y)
      for (int x = static_cast<int>(a[0]); x <= static_cast<int>(b[0]); ++x, ++n) {
        const uint8_t* p = img.at(x, y);
        bright += p[0] + p[1] + p[2];
        red += redness(p);
      }
    return std::array<double, 2>{bright / n, red / n};
  };
  const auto lit_wall = strip(-0.85, -0.65, 1.5), dark_wall = strip(0.65, 0.85, 1.5);
  const auto floor = strip(-0.3, 0.3, -0.5), top = strip(-2.0, -1.4, 1.5);
  std::printf(
      "groove: wall facing the light %.1f, facing away %.1f; floor %.1f (redness %.1f), "
      "top %.1f (%.1f)\n",
      lit_wall[0], dark_wall[0], floor[0], floor[1], top[0], top[1]);
  EXPECT_GT(lit_wall[0], dark_wall[0] + 20)
      << "wall facing the light " << lit_wall[0] << ", facing away " << dark_wall[0];
  EXPECT_GT(floor[0], top[0] + 30) << "floor " << floor[0] << ", top " << top[0];
  EXPECT_GT(floor[1], top[1] + 20) << "floor " << floor[1] << ", top " << top[1];
}

TEST_F(RendererTest, CapsulorhexisOpeningShowsMoreRedThanTheIntactCapsule) {
  Renderer r(plain());
  const Image intact = render(r, *eye_);
  RenderSnapshot opened = *eye_;
  BodyView& capsule = opened.bodies[3];
  ASSERT_EQ(capsule.look, Look::Capsule);
  std::vector<uint32_t> kept;
  for (size_t t = 0; t < capsule.tris.size(); t += 3) {
    Vec3 centroid = Vec3::Zero();
    for (int k = 0; k < 3; ++k)
      for (int c = 0; c < 3; ++c) centroid[c] += capsule.xyz[3 * capsule.tris[t + k] + c] / 3.0;
    if (std::hypot(centroid.x(), centroid.y()) > 2.6)
      kept.insert(kept.end(), capsule.tris.begin() + t, capsule.tris.begin() + t + 3);
  }
  ASSERT_LT(kept.size(), capsule.tris.size());
  capsule.tris = kept;
  capsule.edges = open_edges(kept);
  capsule.topology_version = 2;
  const Image cut = render(r, opened);
  const auto c = px(Vec3::Zero());
  const double inner = 2.2 * px_per_mm();
  double red_intact = 0, red_cut = 0;
  int n = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x)
      if (std::hypot(x + 0.5 - c[0], y + 0.5 - c[1]) < inner) {
        red_intact += redness(intact.at(x, y));
        red_cut += redness(cut.at(x, y));
        ++n;
      }
  red_intact /= n;
  red_cut /= n;
  EXPECT_GT(red_cut, red_intact + 15) << "intact " << red_intact << ", opened " << red_cut;
  // The cut edge draws a pale ring at r = 2.6 mm that the intact capsule does not have.
  auto pale = [](const uint8_t* p) { return p[1] > 200 && p[2] > 170; };
  const double ring_in = 2.4 * px_per_mm(), ring_out = 2.9 * px_per_mm();
  EXPECT_GT(cut.fraction(c[0], c[1], ring_out, pale, ring_in), 0.1);
  EXPECT_LT(intact.fraction(c[0], c[1], ring_out, pale, ring_in), 0.02);
}

TEST_F(RendererTest, EachInstrumentShowsSteelNearItsTip) {
  Renderer r(plain());
  const Vec3 tip(1.0, -0.5, 2.6);
  // The shaft rises toward the surgeon from 3 o'clock, as through a temporal port.
  const Quat quat = Quat::FromTwoVectors(Vec3::UnitZ(), Vec3(1.0, 0.2, 0.6).normalized());
  const Image none = render(r, *eye_);
  const auto t = px(tip);
  const double window = 1.2 * px_per_mm();
  EXPECT_EQ(none.count(t[0], t[1], window, steel), 0);
  for (int k = 0; k < 6; ++k) {
    RenderSnapshot s = *eye_;
    ToolView tool;
    tool.kind = static_cast<ToolKind>(k);
    tool.tip_mm = tip;
    tool.quat = quat;
    s.tools.push_back(tool);
    const Image img = render(r, s);
    EXPECT_GT(img.count(t[0], t[1], window, steel), 15)
        << "tool " << to_string(tool.kind) << " not seen near its projected tip";
  }
}

TEST_F(RendererTest, PhacoTipGlowsAtPedalThree) {
  Renderer r(plain());
  RenderSnapshot s = *eye_;
  ToolView probe;
  probe.kind = ToolKind::PhacoProbe;
  probe.tip_mm = Vec3(0, 0, 2.5);
  probe.quat = Quat::FromTwoVectors(Vec3::UnitZ(), Vec3(1.0, 0, 0.5).normalized());
  s.tools.push_back(probe);
  auto glow = [](const uint8_t* p) { return p[0] > 200 && p[1] > 170 && p[2] < 170; };
  const auto t = px(probe.tip_mm);
  const Image idle = render(r, s);
  s.tools[0].pedal = 3;
  const Image on = render(r, s);
  EXPECT_GT(on.count(t[0], t[1], 0.8 * px_per_mm(), glow),
            idle.count(t[0], t[1], 0.8 * px_per_mm(), glow) + 10);
}

TEST_F(RendererTest, ShadowSlidesAwayAsTheTipRises) {
  // The illuminator is tilted toward 12 o'clock, so a shadow falls toward 6 o'clock (down the
  // image) of its instrument, further the higher the tip is above the lens: the depth cue.
  auto shadow_offset_rows = [&](double height) {
    RenderOptions with = plain(), without = plain();
    without.shadows = false;
    Renderer lit(with), unlit(without);
    RenderSnapshot s = *eye_;
    ToolView probe;
    probe.kind = ToolKind::Aspirator;
    probe.tip_mm = Vec3(0, 0, geometry_->lens_c_anterior + height);
    probe.quat = Quat::FromTwoVectors(Vec3::UnitZ(), Vec3(0.3, 0, 1).normalized());
    s.tools.push_back(probe);
    const Image a = render(lit, s), b = render(unlit, s);
    const auto t = px(probe.tip_mm);
    double rows = 0;
    int n = 0;
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < kW; ++x)
        // A band of columns through the tip: the shaft leans toward 3 o'clock, out of it.
        if (std::abs(x - t[0]) < 0.3 * px_per_mm() && std::abs(y - t[1]) < 2.5 * px_per_mm() &&
            b.at(x, y)[0] > a.at(x, y)[0] + 25) {  // darkened by the shadow
          rows += y - t[1];
          ++n;
        }
    EXPECT_GT(n, 20) << "no shadow near the tip at height " << height;
    return n ? rows / n : 0.0;
  };
  const double low = shadow_offset_rows(0.3), high = shadow_offset_rows(2.5);
  EXPECT_GT(high, low + 0.3 * px_per_mm()) << "low " << low << " px, high " << high << " px";
}

TEST_F(RendererTest, GuidanceCircleAppearsWhereItProjects) {
  RenderSnapshot s = *eye_;
  s.guidance.rhexis_centre_mm = Vec3(0.3, 0.2, geometry_->lens_c_anterior);
  s.guidance.rhexis_diameter_mm = 5.2;
  Renderer r;  // guidance on
  const Image img = render(r, s);
  int hits = 0;
  for (int i = 0; i < 36; ++i) {
    const double a = 2 * kPi * i / 36;
    const auto p = px(*s.guidance.rhexis_centre_mm + 2.6 * Vec3(std::cos(a), std::sin(a), 0));
    hits += img.count(p[0], p[1], 2.5, guidance_green) > 0 ? 1 : 0;
  }
  EXPECT_GE(hits, 34);
  const auto c = px(*s.guidance.rhexis_centre_mm);
  EXPECT_EQ(img.count(c[0], c[1], 1.5 * px_per_mm(), guidance_green), 0);
  s.show_guidance = false;
  const Image hidden = render(r, s);
  EXPECT_EQ(hidden.count(c[0], c[1], 3.0 * px_per_mm(), guidance_green), 0);
}

TEST_F(RendererTest, GlobeRotationMovesTheEyeNotTheTools) {
  Renderer r(plain());
  RenderSnapshot s = *eye_;
  ToolView hook;
  hook.kind = ToolKind::Hook;
  hook.tip_mm = Vec3(-3.0, 3.0, 3.5);
  hook.quat = Quat::FromTwoVectors(Vec3::UnitZ(), Vec3(-1.0, 0.3, 0.5).normalized());
  s.tools.push_back(hook);
  const auto t = px(hook.tip_mm);
  auto pupil_centre_x = [](const Image& img) {
    double sx = 0;
    int n = 0;
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x)
        if (red_reflex(img.at(x, y))) {
          sx += x;
          ++n;
        }
    return n ? sx / n : 0.0;
  };
  const Image straight = render(r, s);
  // 8° about +y: the front of the globe (11 mm above its centre) swings toward +x by ~1.6 mm.
  s.globe_rotation = Quat(Eigen::AngleAxisd(8 * kPi / 180, Vec3::UnitY()));
  const Image turned = render(r, s);
  EXPECT_GT(pupil_centre_x(turned) - pupil_centre_x(straight), 0.8 * px_per_mm());
  EXPECT_GT(turned.count(t[0], t[1], 0.6 * px_per_mm(), steel), 5);
}

TEST_F(RendererTest, SideBySideStereoDrawsTwoSimilarHalves) {
  RenderOptions o = plain();
  o.stereo = StereoMode::SideBySide;
  Renderer r(o);
  const Image img = render(r, *eye_);
  const int half = kW / 2;
  double diff = 0;
  int red_left = 0, red_right = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < half; ++x) {
      const uint8_t *a = img.at(x, y), *b = img.at(x + half, y);
      for (int c = 0; c < 3; ++c) diff += std::abs(a[c] - b[c]);
      red_left += red_reflex(a);
      red_right += red_reflex(b);
    }
  diff /= 3.0 * half * kH;
  EXPECT_GT(red_left, 1000);
  EXPECT_NEAR(red_right, red_left, 0.1 * red_left);
  EXPECT_LT(diff, 25.0);  // the same eye from viewpoints 22 mm apart
  EXPECT_GT(diff, 0.1);   // but not the same picture: the eyes see it from different sides
  // Each half is centred on its own eye's view of the axis.
  EXPECT_TRUE(red_reflex(img.at(half / 2, kH / 2)));
  EXPECT_TRUE(red_reflex(img.at(half + half / 2, kH / 2)));
}

TEST_F(RendererTest, IndexBuffersAreSentOnlyWhenTopologyChanges) {
  Renderer r(plain());
  RenderSnapshot s = *eye_;
  target_->bind();
  const FrameStats first = r.draw(s, {}, kW, kH);
  const FrameStats second = r.draw(s, {}, kW, kH);
  EXPECT_GT(second.triangles, 1000u);
  // One index buffer per body, and the lens's thickness map (sent again only when the lens
  // changes).
  EXPECT_EQ(first.uploads, second.uploads + s.bodies.size() + 1);
  s.bodies[3].topology_version++;
  const FrameStats third = r.draw(s, {}, kW, kH);
  EXPECT_EQ(third.uploads, second.uploads + 1);
}

// The trainer's panels (issue 24): a covered rectangle is left unshaded (the clear colour) and the
// rest of the view is drawn as without it; fill() paints flat opaque rectangles.
TEST_F(RendererTest, ACoveredRectangleIsLeftUnshadedAndFillPaintsIt) {
  Renderer r(plain());
  const Image whole = render(r, *eye_);
  const PixelRect panel{kW / 2.0f - 60, kH / 2.0f - 40, kW / 2.0f + 60, kH / 2.0f + 40};
  target_->bind();
  r.draw(*eye_, {}, kW, kH, {&panel, 1});
  const Image covered{kW, kH, read_pixels(kW, kH)};
  int inside = 0, unshaded = 0, outside = 0, same = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const bool in = x >= panel.x0 && x < panel.x1 && y >= panel.y0 && y < panel.y1;
      const uint8_t *a = whole.at(x, y), *b = covered.at(x, y);
      if (in) {
        ++inside;
        unshaded += background(b) ? 1 : 0;
      } else {
        ++outside;
        same += a[0] == b[0] && a[1] == b[1] && a[2] == b[2] ? 1 : 0;
      }
    }
  EXPECT_EQ(unshaded, inside) << "the eye's centre, red reflex and all, is not drawn under it";
  EXPECT_EQ(same, outside) << "nor is anything else changed";
  EXPECT_TRUE(red_reflex(whole.at(kW / 2, kH / 2)));

  r.fill({&panel, 1}, {0.0f, 0.0f, 1.0f, 1.0f}, kW, kH);
  const Image filled{kW, kH, read_pixels(kW, kH)};
  const uint8_t* c = filled.at(kW / 2, kH / 2);
  EXPECT_EQ(c[0], 0);
  EXPECT_EQ(c[2], 255);
  const uint8_t* below = filled.at(kW / 2, static_cast<int>(panel.y1) + 5);
  EXPECT_EQ(below[0], covered.at(kW / 2, static_cast<int>(panel.y1) + 5)[0]);
}

TEST_F(RendererTest, ScreenshotIsAPngOfTheFrame) {
  Renderer r(plain());
  const Image img = render(r, *eye_);
  const auto file = std::filesystem::temp_directory_path() / "phaco_test_renderer_shot.png";
  save_screenshot(file, kW, kH);
  const cv::Mat png = cv::imread(file.string(), cv::IMREAD_COLOR);
  std::filesystem::remove(file);
  ASSERT_FALSE(png.empty());
  EXPECT_EQ(png.cols, kW);
  EXPECT_EQ(png.rows, kH);
  const cv::Vec3b centre = png.at<cv::Vec3b>(kH / 2, kW / 2);  // BGR
  const uint8_t* expect = img.at(kW / 2, kH / 2);
  EXPECT_EQ(centre[2], expect[0]);
  EXPECT_EQ(centre[1], expect[1]);
  EXPECT_EQ(centre[0], expect[2]);
  EXPECT_THROW(save_screenshot("/nonexistent-dir/x.png", kW, kH), RenderError);
}

}  // namespace
}  // namespace phaco::render
