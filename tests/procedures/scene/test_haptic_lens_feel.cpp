// What the sculpting probe feels (issue 19 item 5, end to end): the scene steps a sculpting
// scenario and publishes its haptic model each frame; between frames the haptic model ticks at
// 1 kHz with the device on the scenario's own track (as `phaco run --haptics scripted` does, but
// deterministic: no threads, no clock). The probe must feel the nucleus — a force while it presses
// without ultrasound, a bounded one while it cuts — and the force must stay finite and continuous
// tick to tick.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "components/tool.hpp"
#include "engine/io/track.hpp"
#include "procedures/scene/haptic_publish.hpp"
#include "procedures/scene/scene.hpp"
#include "systems/haptic_model/haptic_model.hpp"
#include "tests/support/capture_port.hpp"
#include "tests/support/sanitizers.hpp"
#include "tests/support/scene_run.hpp"

namespace phaco {
namespace {

using test::CapturePort;

struct Feel {
  double max_mn = 0;                      // largest force
  double rms_contact_mn = 0;              // over the ticks with a force
  double rms_cut_mn = 0;                  // over the ticks at pedal 3 with a force
  double rms_press_mn = 0;                // over the ticks below pedal 3 with a force
  double max_jump_mn = 0, jump_at_s = 0;  // largest change between two ticks, and when
  uint64_t ticks = 0, contact_ticks = 0, cut_ticks = 0, press_ticks = 0;
  bool finite = true;
};

Feel feel(Scenario s, double seconds, const haptic_model::HapticSettings& settings,
          bool with_patch) {
  s.duration_s = std::min(s.duration_s, seconds);
  CapturePort port;
  SceneOptions o;
  o.cache_dir = test::scene_cache_dir();
  o.haptics = &port;
  auto scene = build_scene(s, o);
  const HandTrack* probe = nullptr;
  for (const HandTrack& h : s.hands)
    if (h.tool == ToolKind::PhacoProbe) probe = &h;
  if (!probe) return {};
  const size_t hand = static_cast<size_t>(probe->hand);
  auto state = std::make_unique<haptic_model::HapticToolState>();
  Feel f;
  double sum2 = 0, cut2 = 0, press2 = 0;
  Vec3 last = Vec3::Zero(), last_pos = sample_track(probe->track, 0).pos;
  uint64_t tick = 0;
  const uint64_t frames = s.frame_count();
  for (uint64_t frame = 0; frame < frames; ++frame) {
    step(*scene);
    if (!with_patch) port.slot.tools[hand].triangle_count = 0;
    haptic_model::adopt_model(port.slot.tools[hand], *state, settings);
    for (; tick * settings.dt_s < scene->time_s; ++tick) {
      const ToolPose pose = sample_track(probe->track, tick * settings.dt_s);
      const Vec3 vel = (pose.pos - last_pos) / settings.dt_s;
      last_pos = pose.pos;
      const haptic_model::HapticForce hf =
          haptic_model::haptic_tick(state->newest_model(), pose.pos, vel, settings, *state);
      const double mag = hf.force_mn.norm();
      f.finite = f.finite && std::isfinite(mag);
      ++f.ticks;
      f.max_mn = std::max(f.max_mn, mag);
      const double jump = tick > 0 ? (hf.force_mn - last).norm() : 0.0;
      if (jump > f.max_jump_mn) f.max_jump_mn = jump, f.jump_at_s = tick * settings.dt_s;
      last = hf.force_mn;
      if (mag > 0) {
        ++f.contact_ticks, sum2 += mag * mag;
        if (pose.pedal >= 3.0) {
          ++f.cut_ticks, cut2 += mag * mag;
        } else {
          ++f.press_ticks, press2 += mag * mag;
        }
      }
    }
  }
  auto rms = [](double s2, uint64_t n) { return n ? std::sqrt(s2 / double(n)) : 0.0; };
  f.rms_contact_mn = rms(sum2, f.contact_ticks);
  f.rms_cut_mn = rms(cut2, f.cut_ticks);
  f.rms_press_mn = rms(press2, f.press_ticks);
  return f;
}

void print(const char* what, const Feel& f) {
  std::printf(
      "%s: %llu ticks, %llu in contact (%llu cutting, %llu pressing); max %.2f mN, RMS in contact "
      "%.2f mN (cutting %.2f, pressing %.2f); max tick-to-tick change %.3f mN at %.3f s (%.2f %% "
      "of the max)\n",
      what, (unsigned long long)f.ticks, (unsigned long long)f.contact_ticks,
      (unsigned long long)f.cut_ticks, (unsigned long long)f.press_ticks, f.max_mn,
      f.rms_contact_mn, f.rms_cut_mn, f.rms_press_mn, f.max_jump_mn, f.jump_at_s,
      100.0 * f.max_jump_mn / std::max(1e-12, f.max_mn));
}

// The demo's first trench (level 3), both lens models. The capsule's patch is left out of the
// model: at 0.68 s, where the probe passes the rhexis rim, it chatters on its own (a 40 mN
// change between ticks with no lens in the model; the capsule's contact, not this issue's).
// Continuity, end to end: ≤ 12.5 % of the largest force between ticks — NOT the 5 % the
// synthetic trench tests hold (test_sphere_contacts.cpp): while the probe cuts, each frame's
// removal under the tip changes the material more than the 4 ms crossfade hides (measured 9.6 %
// tets, 8.4 % fragments, ≈ 3–4 mN on a ≈ 15 mN cut; docs/haptic_model.md, "Limits").
// Under ASan only the fragment lens (seed 002's cells, the nucleus drill's model): both models'
// 12 s at level 3 took 255 s there on a loaded machine, the fragment lens alone 70 s. The tet
// lens's haptic spheres run under ASan in
// HapticPublish.TheSculptedLensComesAsSpheresOfItsMaterialNearTheTip.
TEST(HapticLensFeel, TheSculptingProbeFeelsTheNucleusContinuously) {
  const std::vector<const char*> models = test::kUnderAsan
                                              ? std::vector<const char*>{"fragments"}
                                              : std::vector<const char*>{"tets", "fragments"};
  for (const char* model : models) {
    Scenario s = test::repo_scenario("phaco_sculpting_demo.json");
    s.methods["lens.model"] = model;
    haptic_model::HapticSettings settings;
    settings.blend_max_step_mn = 0.25;  // as the capsule's continuity test
    const Feel f = feel(s, 12.0, settings, false);
    print(model, f);
    EXPECT_TRUE(f.finite) << model;
    EXPECT_GT(f.contact_ticks, 1000u) << model << ": the probe feels the lens";
    EXPECT_GT(f.cut_ticks, 1000u) << model;
    EXPECT_GT(f.press_ticks, 1000u) << model;
    EXPECT_GT(f.rms_press_mn, f.rms_cut_mn) << model << ": the nucleus yields under ultrasound";
    EXPECT_LE(f.rms_cut_mn, settings.max_force_mn) << model;
    EXPECT_LE(f.max_mn, 200.0) << model << ": mN of the nucleus, far inside the device's range";
    EXPECT_LE(f.max_jump_mn, 0.125 * f.max_mn) << model << " at " << f.jump_at_s << " s";
  }
}

// The expert's whole drill (57 s at level 3): the figures for the note. Run by name:
// --gtest_also_run_disabled_tests --gtest_filter=*Expert*
TEST(HapticLensFeel, DISABLED_ExpertFigures) {
  const Scenario s = test::repo_scenario("phaco_sculpting_expert.json");
  haptic_model::HapticSettings settings;
  const Feel f = feel(s, s.duration_s, settings, true);
  print("expert, whole model, default settings", f);
  print("expert, lens only, default settings", feel(s, s.duration_s, settings, false));
  EXPECT_TRUE(f.finite);
}

}  // namespace
}  // namespace phaco
