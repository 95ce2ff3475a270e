// The publish side of the haptic handoff (procedures/scene/haptic_publish): the local model the
// 1 kHz thread gets must be the capsule as the simulation has it near the tool — every free node
// with all of its springs (so the local forces on it are the full mesh's), held by an anchored
// ring — and must follow the tools (grasp, distance, lens).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>

#include "components/held_fragment.hpp"
#include "components/particles.hpp"
#include "components/tool.hpp"
#include "procedures/scene/capsule_cutting.hpp"
#include "procedures/scene/capsule_physics.hpp"
#include "procedures/scene/haptic_publish.hpp"
#include "procedures/scene/lens_fragments.hpp"
#include "procedures/scene/lens_sculpting.hpp"
#include "procedures/scene/scene.hpp"
#include "systems/haptic_model/haptic_model.hpp"
#include "tests/support/capture_port.hpp"
#include "tests/support/sanitizers.hpp"
#include "tests/support/scene_run.hpp"

namespace phaco {
namespace {

using test::CapturePort;

std::unique_ptr<Scene> scene_at(const char* scenario, double t_s, CapturePort& port) {
  const Scenario s = test::repo_scenario(scenario);
  SceneOptions o;
  o.cache_dir = test::scene_cache_dir();
  o.haptics = &port;
  auto scene = build_scene(s, o);
  const auto frames = static_cast<uint64_t>(std::llround(t_s / s.dt_s));
  for (uint64_t f = 0; f < frames; ++f) step(*scene);
  return scene;
}

const HapticTool& tool_in(const HapticModel& m, Hand hand) {
  return m.tools[static_cast<size_t>(hand)];
}

TEST(HapticPublish, TheGraspedFlapComesWithItsWholeNeighbourhood) {
  CapturePort port;
  // At 4.0 s the demo's forceps (left hand) hold the flap and pull it round.
  auto scene = scene_at("capsulorhexis_demo.json", 4.0, port);
  EXPECT_EQ(port.published, scene->frame) << "one model per frame";
  EXPECT_EQ(port.last_sequence, scene->frame) << "sequence numbers count the publishes";

  const HapticTool& t = tool_in(port.slot, Hand::Left);
  ASSERT_TRUE(t.present);
  EXPECT_EQ(t.tool_kind, static_cast<uint8_t>(ToolKind::Forceps));
  ASSERT_NE(t.grasped_node, kHapticNoNode) << "the forceps hold the flap at 4 s";
  EXPECT_EQ(t.kind[t.grasped_node], HapticNodeKind::Grasped);
  ASSERT_GT(t.node_count, 20u);
  ASSERT_LE(t.node_count, kHapticMaxNodes);
  EXPECT_GT(t.spring_count, t.node_count) << "a membrane has more springs than nodes";
  EXPECT_GT(t.triangle_count, 0u);
  EXPECT_GT(t.damping_mn_s_per_mm, 0.0f);

  const Entity capsule = *scene->body(BodyPart::Capsule);
  const Particles& p = scene->world.at<Particles>(capsule);
  const CapsuleSprings& cp = scene->world.at<CapsuleSprings>(capsule);
  const auto& g = scene->world.at<ToolGrasp>(scene->tools[0]);
  ASSERT_TRUE(g.capsule.holding());

  // Map local nodes back to particles by position (the model carries no global index).
  std::vector<uint32_t> particle_of(t.node_count, kInvalidIndex);
  for (uint32_t l = 0; l < t.node_count; ++l) {
    for (uint32_t i = 0; i < p.slots.size(); ++i) {
      if (p.slots.alive(i) && p.x[i] == t.x[l] && p.y[i] == t.y[l] && p.z[i] == t.z[l]) {
        particle_of[l] = i;
        break;
      }
    }
    ASSERT_NE(particle_of[l], kInvalidIndex) << "node " << l << " is a capsule particle";
    const float inv = p.inv_mass[particle_of[l]];
    EXPECT_FLOAT_EQ(t.mass[l], inv > 0 ? 1.0f / inv : 0.0f);
  }
  EXPECT_EQ(particle_of[t.grasped_node], g.capsule.particle);

  // Every free node carries all of its springs, with the scene's rest length and stiffness.
  uint32_t free_nodes = 0;
  for (uint32_t l = 0; l < t.node_count; ++l) {
    if (t.kind[l] != HapticNodeKind::Free) continue;
    ++free_nodes;
    const uint32_t i = particle_of[l];
    std::multiset<std::pair<float, float>> scene_springs, model_springs;
    for (uint32_t k = cp.graph.begin(i); k < cp.graph.end(i); ++k) {
      const uint32_t sp = cp.graph.spring[k];
      scene_springs.insert({cp.springs.rest_length[sp], cp.springs.stiffness[sp]});
    }
    for (uint32_t s = 0; s < t.spring_count; ++s) {
      if (t.spring_i[s] == l || t.spring_j[s] == l)
        model_springs.insert({t.rest_mm[s], t.k_mn_per_mm[s]});
    }
    EXPECT_EQ(scene_springs, model_springs) << "free node " << l << " (particle " << i << ")";
  }
  EXPECT_GT(free_nodes, 10u);
  for (uint32_t s = 0; s < t.spring_count; ++s) {
    ASSERT_LT(t.spring_i[s], t.node_count);
    ASSERT_LT(t.spring_j[s], t.node_count);
    EXPECT_FALSE(t.kind[t.spring_i[s]] == HapticNodeKind::Anchored &&
                 t.kind[t.spring_j[s]] == HapticNodeKind::Anchored)
        << "a spring between two anchors does nothing";
  }
  for (uint32_t f = 0; f < t.triangle_count; ++f) {
    for (uint16_t c : t.triangles[f]) EXPECT_LT(c, t.node_count);
  }
  EXPECT_TRUE(t.lens_present) << "the rhexis scene has the lens under the capsule";
  EXPECT_GT(t.lens_stiffness_mn_per_mm, 0.0f);
}

// The local searches (bins re-binned from the active set, the ball's triangle fans) give what
// whole-mesh scans give: at every 10th frame of the demo, for every tool near the capsule and not
// holding it, the seed is the particle nearest the tip, and the patch holds every triangle with
// three local corners.
TEST(HapticPublish, LocalSearchesMatchWholeMeshScans) {
  const Scenario s = test::repo_scenario("capsulorhexis_demo.json");
  CapturePort port;
  SceneOptions o;
  o.cache_dir = test::scene_cache_dir();
  o.haptics = &port;
  auto scene = build_scene(s, o);
  const HapticPublishSettings settings = haptic_publish_settings(*scene);
  HapticPublishScratch warm;
  HapticModel model;
  const Entity capsule = *scene->body(BodyPart::Capsule);
  uint32_t compared_seeds = 0, compared_patches = 0;
  const auto frames = static_cast<uint64_t>(std::llround(8.0 / s.dt_s));
  for (uint64_t f = 0; f < frames; ++f) {
    step(*scene);
    build_haptic_model(*scene, settings, warm, model);  // every frame, as the system does
    if (f % 10 != 0) continue;
    const Particles& p = scene->world.at<Particles>(capsule);
    const Triangles& tris = scene->world.at<Triangles>(capsule);
    for (Entity tool : scene->tools) {
      const Vec3 tip = scene->world.at<ToolState>(tool).pos;
      const HapticTool& t = model.tools[static_cast<size_t>(scene->world.at<Tool>(tool).hand)];
      if (t.node_count == 0 || t.grasped_node != kHapticNoNode) continue;
      double best = std::numeric_limits<double>::infinity();  // over every live particle
      for (uint32_t i = 0; i < p.slots.size(); ++i) {
        if (!p.slots.alive(i)) continue;
        const double dx = p.x[i] - tip.x(), dy = p.y[i] - tip.y(), dz = p.z[i] - tip.z();
        best = std::min(best, dx * dx + dy * dy + dz * dz);
      }
      const double sx = t.x[0] - tip.x(), sy = t.y[0] - tip.y(), sz = t.z[0] - tip.z();  // the seed
      EXPECT_EQ(sx * sx + sy * sy + sz * sz, best) << "frame " << f;
      ++compared_seeds;
    }
    // The patch of the last tool built: every triangle whose corners are all local, by scan.
    if (warm.nodes.empty()) continue;
    const auto local = [&](uint32_t v) {
      return std::find(warm.nodes.begin(), warm.nodes.end(), v) != warm.nodes.end();
    };
    size_t local_triangles = 0;
    for (uint32_t fi = 0; fi < tris.slots.size(); ++fi)
      local_triangles +=
          tris.slots.alive(fi) && local(tris.a[fi]) && local(tris.b[fi]) && local(tris.c[fi]);
    EXPECT_EQ(warm.near_triangles.size(), local_triangles) << "frame " << f;
    ++compared_patches;
  }
  EXPECT_GT(compared_seeds, 5u) << "the tools come near the capsule in the demo";
  EXPECT_GT(compared_patches, 5u);
}

// Issue 17 item 5: the device feels the tear's plateau. While the expert's forceps tear the flap,
// the published model carries the capsule's tear resistance as the grasp's limit, and the haptic
// thread's force for the held flap stays within it however hard the device pulls; the same model
// without the limit gives far more.
TEST(HapticPublish, TheHeldFlapOfAnOpenTearIsFeltUpToTheTearResistance) {
  CapturePort port;
  const Scenario s = test::repo_scenario("capsulorhexis_expert.json");
  SceneOptions o;
  o.cache_dir = test::scene_cache_dir();
  o.haptics = &port;
  auto scene = build_scene(s, o);
  const Entity capsule = *scene->body(BodyPart::Capsule);
  int tearing_frames = 0;
  for (uint64_t f = 0; f < 2000 && tearing_frames < 30; ++f) {
    step(*scene);
    tearing_frames += scene->world.at<CapsuleCutting>(capsule).tearing;
  }
  ASSERT_EQ(tearing_frames, 30) << "the expert tears";
  const CapsuleCutting& cc = scene->world.at<CapsuleCutting>(capsule);
  const HapticTool& t = tool_in(port.slot, Hand::Left);
  ASSERT_NE(t.grasped_node, kHapticNoNode);
  EXPECT_FLOAT_EQ(t.grasp_limit_mn, float(cc.tear.threshold_mn));
  EXPECT_GT(t.grasp_limit_mn, 5.0f);
  const Vec3 held(t.x[t.grasped_node], t.y[t.grasped_node], t.z[t.grasped_node]);
  haptic_model::HapticSettings hs;
  for (double pull_mm : {0.5, 2.0}) {
    double felt[2] = {0, 0};
    for (int limited = 0; limited < 2; ++limited) {
      auto model = std::make_unique<HapticTool>(t);
      if (!limited) model->grasp_limit_mn = 0;
      auto st = std::make_unique<haptic_model::HapticToolState>();
      haptic_model::adopt_model(*model, *st, hs);
      haptic_model::HapticForce f;
      for (int k = 0; k < 300; ++k)
        f = haptic_model::haptic_tick(*model, held + Vec3(0, 0, pull_mm), Vec3::Zero(), hs, *st);
      felt[limited] = f.force_mn.norm();
    }
    EXPECT_LE(felt[1], cc.tear.threshold_mn + 1e-3) << pull_mm;
    if (pull_mm >= 2.0) {
      EXPECT_GT(felt[0], 2 * cc.tear.threshold_mn) << "without the limit: felt in full";
    }
  }
}

TEST(HapticPublish, ATipFarFromTheCapsuleGetsNoNodes) {
  CapturePort port;
  // At the start the cystotome (right hand) waits at z = 3.5, 1.7 mm above the capsule.
  auto scene = scene_at("capsulorhexis_demo.json", 1.0 / 60.0, port);
  const HapticTool& t = tool_in(port.slot, Hand::Right);
  ASSERT_TRUE(t.present);
  EXPECT_EQ(t.tool_kind, static_cast<uint8_t>(ToolKind::Cystotome));
  EXPECT_EQ(t.node_count, 0u);
  EXPECT_EQ(t.spring_count, 0u);
  EXPECT_EQ(t.triangle_count, 0u);
  EXPECT_EQ(t.grasped_node, kHapticNoNode);
  const ToolState& pose = scene->world.at<ToolState>(scene->tools[1]);
  EXPECT_EQ(t.tip_mm[2], static_cast<float>(pose.pos.z())) << "the tip where the simulation has it";
  EXPECT_GT(t.tip_mm[2], 3.0f);
}

TEST(HapticPublish, TheBallGrowsWithTheHopsAndStaysWithinCapacity) {
  CapturePort port;
  auto scene = scene_at("capsulorhexis_demo.json", 4.0, port);
  HapticPublishScratch scratch;
  HapticModel m;
  uint32_t previous = 0;
  for (uint32_t hops : {1u, 3u, 5u, 8u, 20u}) {
    HapticPublishSettings s = haptic_publish_settings(*scene);
    s.active_hops = hops;
    build_haptic_model(*scene, s, scratch, m);
    const HapticTool& t = tool_in(m, Hand::Left);
    EXPECT_GE(t.node_count, previous) << hops << " hops";
    EXPECT_LE(t.node_count, kHapticMaxNodes);
    EXPECT_LE(t.spring_count, kHapticMaxSprings);
    previous = t.node_count;
  }
  // 20 hops would take the whole flap: the ball stops a layer early, that layer anchored, so
  // the model nearly fills its capacity and every free node still has its springs (below).
  EXPECT_GT(previous, kHapticMaxNodes * 3 / 4) << "20 hops fill the model to near capacity";
  {
    const HapticTool& t = tool_in(m, Hand::Left);
    std::vector<uint32_t> degree(t.node_count, 0);
    for (uint32_t s = 0; s < t.spring_count; ++s) ++degree[t.spring_i[s]], ++degree[t.spring_j[s]];
    uint32_t anchored = 0;
    for (uint32_t l = 0; l < t.node_count; ++l) {
      if (t.kind[l] == HapticNodeKind::Anchored)
        ++anchored;
      else
        EXPECT_GE(degree[l], 2u) << "a free node held by its springs";
    }
    EXPECT_GT(anchored, 0u) << "the outer layer holds the ball";
  }
  // The scratch marks are cleared after each build: a second build gives the same model.
  HapticModel again;
  HapticPublishSettings s = haptic_publish_settings(*scene);
  build_haptic_model(*scene, s, scratch, m);
  build_haptic_model(*scene, s, scratch, again);
  const HapticTool &a = tool_in(m, Hand::Left), &b = tool_in(again, Hand::Left);
  ASSERT_EQ(a.node_count, b.node_count);
  ASSERT_EQ(a.spring_count, b.spring_count);
  for (uint32_t l = 0; l < a.node_count; ++l) EXPECT_EQ(a.x[l], b.x[l]);
}

// Issue 19 item 5: the sculpted lens is published as spheres of its material near every tip — the
// alive surface tets within reach, turned with the nucleus, nearest first, none of the sculpted
// ones — and the probe at pedal 3 carries the cut force; the analytic lens is not sent.
TEST(HapticPublish, TheSculptedLensComesAsSpheresOfItsMaterialNearTheTip) {
  CapturePort port;
  // At 9 s the demo's probe is in its first trench with ultrasound on.
  auto scene = scene_at("phaco_sculpting_demo.json", 9.0, port);
  const Entity lens = *scene->body(BodyPart::Lens);
  const LensSculpting& ls = scene->world.at<LensSculpting>(lens);
  ASSERT_LT(ls.topology.alive_count, ls.topology.tet_count) << "the demo has sculpted by 9 s";
  const HapticPublishSettings settings = haptic_publish_settings(*scene);
  bool saw_probe = false;
  for (Entity e : scene->tools) {
    const HapticTool& t = port.slot.tools[static_cast<size_t>(scene->world.at<Tool>(e).hand)];
    ASSERT_TRUE(t.present);
    EXPECT_FALSE(t.lens_present) << "the sculpted lens is not the analytic ellipsoid any more";
    const ToolState& pose = scene->world.at<ToolState>(e);
    const double reach = t.tip_radius_mm + settings.lens.reach_mm;
    const double c = std::cos(ls.rotation.angle_rad), sn = std::sin(ls.rotation.angle_rad);
    // Every alive surface tet within reach (brute force over the mesh), in the world.
    std::vector<std::pair<double, Vec3>> expected;
    for (uint32_t k = 0; k < ls.topology.tet_count; ++k) {
      if (!ls.topology.alive[k] || ls.topology.surface_slot[k] == kNoTet) continue;
      const Vec3 r = sculpt::tet_centre(ls.topology, k);
      const Vec3 w(c * r.x() - sn * r.y(), sn * r.x() + c * r.y(), r.z());
      const double radius = std::cbrt(3.0 * ls.topology.volume[k] / (4.0 * 3.14159265358979));
      const double gap = (w - pose.pos).norm() - radius;
      if (gap <= reach) expected.emplace_back(gap, w);
    }
    std::sort(expected.begin(), expected.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    EXPECT_EQ(t.sphere_count, std::min<size_t>(expected.size(), kHapticMaxSpheres));
    double last_gap = -1e9;
    for (uint32_t j = 0; j < t.sphere_count; ++j) {
      const Vec3 centre(t.sphere_x[j], t.sphere_y[j], t.sphere_z[j]);
      const double gap = (centre - pose.pos).norm() - t.sphere_r[j];
      EXPECT_LE(gap, reach + 1e-4);
      EXPECT_GE(gap, last_gap - 1e-4) << "nearest first";
      last_gap = gap;
      const bool found = std::any_of(expected.begin(), expected.end(), [&](const auto& x) {
        return (x.second - centre).norm() < 1e-4;
      });
      EXPECT_TRUE(found) << "sphere " << j << " is an alive surface tet";
      EXPECT_GT(t.sphere_r[j], 0.0f);
      EXPECT_NEAR(t.sphere_k[j] / settings.lens.stiffness_mn_mm, 1.0, 0.5 + 1e-6)
          << "k_f at the standard hardness (the cortex at half)";
    }
    if (scene->world.at<Tool>(e).kind == ToolKind::PhacoProbe) {
      saw_probe = true;
      EXPECT_GT(t.sphere_count, 10u) << "the probe is in the lens";
      EXPECT_NEAR(t.tip_radius_mm, 0.45f, 1e-6);
      if (pose.pedal >= 3.0) {
        EXPECT_NEAR(t.cut_force_mn, settings.lens.cut_force_mn, 1e-4) << "standard eye, power 1";
      } else {
        EXPECT_EQ(t.cut_force_mn, 0.0f);
      }
    } else {
      EXPECT_EQ(t.cut_force_mn, 0.0f) << "only the probe's ultrasound cuts";
    }
  }
  EXPECT_TRUE(saw_probe);
}

// A fragment lens's cells a tool should feel, by a plain scan of every cell in double: alive, with
// an external face, not of the held fragment, gap to the tip within the tool's reach; nearest
// first (ties by id), at most kHapticMaxSpheres.
std::vector<std::pair<float, uint32_t>> nearest_outer_cells(const LensFragments& lf,
                                                            const HapticTool& t, const Vec3& tip,
                                                            double reach_mm) {
  const SimplexCells& cells = lf.lens.cells;
  const double reach = t.tip_radius_mm + reach_mm;
  std::vector<std::pair<float, uint32_t>> want;
  for (uint32_t c = 0; c < cells.size(); ++c) {
    if (!cells.alive[c]) continue;
    if (t.held.held && lf.lens.fragments.label[c] == t.held.fragment) continue;
    bool outer = false;
    for (uint32_t k = 0; k < 4; ++k) outer |= cells.neighbour[c][k] == kNoSimplex;
    if (!outer) continue;
    const double dx = cells.x[c] - tip.x(), dy = cells.y[c] - tip.y(), dz = cells.z[c] - tip.z();
    const double gap =
        std::sqrt(dx * dx + dy * dy + dz * dz) -
        std::cbrt(3.0 * std::max(0.0, static_cast<double>(cells.volume[c])) / (4.0 * M_PI));
    if (gap <= reach) want.emplace_back(static_cast<float>(gap), c);
  }
  std::sort(want.begin(), want.end());
  want.resize(std::min<size_t>(want.size(), kHapticMaxSpheres));
  return want;
}

// The nucleus drill's two tips, probe and chopper, inside a cracked lens: each tool's spheres are
// the nearest outer cells within its reach that a plain scan of every cell in double finds, whether
// the publisher scanned the centres once for both tips (scan_lens_cells) or each tip alone.
TEST(HapticPublish, OneScanForBothTipsFindsWhatAPlainScanOfEveryCellFinds) {
  CapturePort port;
  Scenario s = test::repo_scenario("nucleus_removal_expert.json");
  s.eye.level = 0;
  SceneOptions o;
  o.cache_dir = test::scene_cache_dir();
  o.haptics = &port;
  auto scene = build_scene(s, o);
  const LensFragments& lf = scene->world.at<LensFragments>(*scene->body(BodyPart::Lens));
  const SimplexCells& cells = lf.lens.cells;
  const HapticPublishSettings settings = haptic_publish_settings(*scene);
  const auto expect_spheres = [&](const HapticTool& t,
                                  const std::vector<std::pair<float, uint32_t>>& want,
                                  const char* how) {
    ASSERT_EQ(t.sphere_count, want.size()) << how;
    for (uint32_t j = 0; j < t.sphere_count; ++j) {
      const uint32_t c = want[j].second;
      EXPECT_EQ(t.sphere_x[j], cells.x[c]) << how << " " << j;
      EXPECT_EQ(t.sphere_y[j], cells.y[c]) << how << " " << j;
      EXPECT_EQ(t.sphere_z[j], cells.z[c]) << how << " " << j;
    }
  };
  // Checked at three moments of the expert's first 25 s (both tips at work in the lens).
  int checked_with_spheres = 0;
  for (const double at_s : {8.0, 16.0, 25.0}) {
    while (scene->time_s < at_s) step(*scene);
    for (const Entity e : scene->tools) {
      const HapticTool& t =
          port.slot.tools[static_cast<size_t>(scene->world.at<Tool>(e).hand) % kHapticTools];
      const auto want =
          nearest_outer_cells(lf, t, scene->world.at<ToolState>(e).pos, settings.lens.reach_mm);
      expect_spheres(t, want, "published");
      checked_with_spheres += want.empty() ? 0 : 1;
      // The same tool's spheres from a scratch that scanned nothing: its own scan.
      HapticLensScratch alone;
      HapticTool u = t;
      fill_lens_contacts(*scene, e, settings.lens, alone, u);
      expect_spheres(u, want, "scanned alone");
    }
  }
  EXPECT_GE(checked_with_spheres, 3) << "tips near the lens at least three times";
}

// The fragment lens: boundary cells near the tip, and a held fragment's record copied as is with
// its own cells left out (they ride the tip).
TEST(HapticPublish, TheFragmentLensComesAsItsBoundaryCellsAndAHeldFragmentAsItsRecord) {
  CapturePort port;
  Scenario s = test::repo_scenario("phaco_sculpting_demo.json");
  s.eye.level = 0;
  s.methods["lens.model"] = "fragments";
  SceneOptions o;
  o.cache_dir = test::scene_cache_dir();
  o.haptics = &port;
  auto scene = build_scene(s, o);
  for (int f = 0; f < int(9.0 / s.dt_s); ++f) step(*scene);
  const Entity lens = *scene->body(BodyPart::Lens);
  const LensFragments& lf = scene->world.at<LensFragments>(lens);
  Entity probe{};
  for (Entity e : scene->tools)
    if (scene->world.at<Tool>(e).kind == ToolKind::PhacoProbe) probe = e;
  const ToolState& pose = scene->world.at<ToolState>(probe);
  const HapticTool& t = port.slot.tools[static_cast<size_t>(scene->world.at<Tool>(probe).hand)];
  ASSERT_GT(t.sphere_count, 0u);
  EXPECT_FALSE(t.lens_present);
  auto is_boundary_cell = [&](const Vec3& centre) {
    for (uint32_t c = 0; c < lf.lens.cells.size(); ++c) {
      if (!lf.lens.cells.alive[c]) continue;
      if (Vec3(lf.lens.cells.x[c], lf.lens.cells.y[c], lf.lens.cells.z[c]) != centre) continue;
      for (uint32_t k = 0; k < 4; ++k)
        if (lf.lens.cells.neighbour[c][k] == kNoSimplex) return true;
    }
    return false;
  };
  for (uint32_t j = 0; j < t.sphere_count; ++j) {
    const Vec3 centre(t.sphere_x[j], t.sphere_y[j], t.sphere_z[j]);
    EXPECT_TRUE(is_boundary_cell(centre)) << j;
    EXPECT_LE((centre - pose.pos).norm() - t.sphere_r[j],
              t.tip_radius_mm + haptic_publish_settings(*scene).lens.reach_mm + 1e-4);
  }
  // None missed: the spheres are the nearest boundary cells within reach that a plain scan of
  // every cell in double finds (the publisher's float pre-test only drops cells beyond reach).
  {
    const SimplexCells& cells = lf.lens.cells;
    const auto want =
        nearest_outer_cells(lf, t, pose.pos, haptic_publish_settings(*scene).lens.reach_mm);
    ASSERT_GT(want.size(), 0u);
    ASSERT_EQ(t.sphere_count, want.size());
    for (uint32_t j = 0; j < t.sphere_count; ++j) {
      const uint32_t c = want[j].second;
      EXPECT_EQ(t.sphere_x[j], cells.x[c]) << j;
      EXPECT_EQ(t.sphere_y[j], cells.y[c]) << j;
      EXPECT_EQ(t.sphere_z[j], cells.z[c]) << j;
    }
  }

  // The drill's aspiration holds fragment 0 at the probe (synthetic: set as its code would).
  HeldFragment held;
  held.held = true;
  held.fragment = 0;
  held.mass_kg = 4e-5f;
  held.drag_mn_s_per_mm = 0.04f;
  held.weight_mn = {0, 0, -0.03f};
  held.hold_limit_mn = 11.0f;
  scene->world.add(probe, held);
  HapticPublishScratch scratch;
  HapticModel m;
  build_haptic_model(*scene, haptic_publish_settings(*scene), scratch, m);
  const HapticTool& h = m.tools[static_cast<size_t>(scene->world.at<Tool>(probe).hand)];
  EXPECT_TRUE(h.held.held);
  EXPECT_EQ(h.held.fragment, 0u);
  EXPECT_EQ(h.held.mass_kg, 4e-5f);
  EXPECT_EQ(h.held.hold_limit_mn, 11.0f);
  if (lf.lens.fragments.count == 1) {
    EXPECT_EQ(h.sphere_count, 0u) << "the whole lens is held";
  }
  for (uint32_t j = 0; j < h.sphere_count; ++j) {
    const Vec3 centre(h.sphere_x[j], h.sphere_y[j], h.sphere_z[j]);
    for (uint32_t c = 0; c < lf.lens.cells.size(); ++c) {
      if (Vec3(lf.lens.cells.x[c], lf.lens.cells.y[c], lf.lens.cells.z[c]) == centre &&
          lf.lens.cells.alive[c]) {
        EXPECT_NE(lf.lens.fragments.label[c], 0u) << "the held fragment's cells ride the tip";
      }
    }
  }
}

// The nucleus_removal drill's own aspiration fills the probe's held-fragment record (no synthetic
// record): while the expert holds a quadrant, the published model carries it with its mass, its
// weight less buoyancy, Stokes drag and the vacuum's grip, each against its formula.
// Release only: the expert first holds a quadrant after its cracks, over half its 110 s drill in,
// which ASan at -O1 took 300 s to reach (CI's whole ASan pass is ~20 min). The same publishing
// code runs under ASan in TheFragmentLensComesAsItsBoundaryCellsAndAHeldFragmentAsItsRecord.
TEST(HapticPublish, TheDrillsAspirationPublishesTheQuadrantItHolds) {
  if (test::kUnderAsan) GTEST_SKIP() << "Release only: 300 s under ASan (see above)";
  CapturePort port;
  Scenario s = test::repo_scenario("nucleus_removal_expert.json");
  // At the scenario's own level (1). At level 0 the expert held nothing over its whole run (seen
  // once; why is for the nucleus study's level-0 figures).
  SceneOptions o;
  o.cache_dir = test::scene_cache_dir();
  o.haptics = &port;
  auto scene = build_scene(s, o);
  const Entity lens = *scene->body(BodyPart::Lens);
  Entity probe{};
  for (Entity e : scene->tools)
    if (scene->world.at<Tool>(e).kind == ToolKind::PhacoProbe) probe = e;
  const size_t hand = static_cast<size_t>(scene->world.at<Tool>(probe).hand);
  int held_frames = 0;
  for (uint64_t f = 0; f < static_cast<uint64_t>(s.duration_s / s.dt_s) && held_frames < 20; ++f) {
    step(*scene);
    const LensFragments& lf = scene->world.at<LensFragments>(lens);
    const HeldFragment& record = scene->world.at<HeldFragment>(probe);
    const HeldFragment& published = port.slot.tools[hand].held;
    EXPECT_EQ(record.held, published.held) << "frame " << f;
    if (!record.held) continue;
    ++held_frames;
    const lens::FragmentLens& l = lf.lens;
    ASSERT_LT(record.fragment, l.fragments.count);
    const double m = l.fragments.mass[record.fragment];
    EXPECT_FLOAT_EQ(record.mass_kg, static_cast<float>(m));
    EXPECT_FLOAT_EQ(record.weight_mn[2], static_cast<float>(-m * l.settings.fluid.gravity_mm_s2));
    const double r = std::cbrt(3 * (m / l.settings.density_kg_mm3) / (4 * M_PI));
    EXPECT_NEAR(record.drag_mn_s_per_mm, 6 * M_PI * 1e-6 * r, 1e-9);
    EXPECT_FLOAT_EQ(record.hold_limit_mn, static_cast<float>(lens_tools::holding_force_mn(
                                              l.vacuum_mmhg, l.settings.fluid)));
    EXPECT_GT(record.hold_limit_mn, 0.0f);
    EXPECT_EQ(published.fragment, record.fragment);
    EXPECT_EQ(published.mass_kg, record.mass_kg);
  }
  EXPECT_GE(held_frames, 20) << "the expert never held a fragment";
}

}  // namespace
}  // namespace phaco
