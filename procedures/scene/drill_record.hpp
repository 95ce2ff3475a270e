#pragma once
// Internal to procedures/scene's drill metrics (drill_metrics.hpp): the record the Metrics-phase
// system keeps while a drill runs (per hand: samples, counters and event state; the drill's
// events) and the anatomy its detectors test against. Written by drill_events.cpp, read by the
// measures (drill_measures.cpp) and the report (drill_metrics.cpp).
#include <cstdint>
#include <optional>
#include <vector>

#include "components/haptic_model.hpp"
#include "components/tool.hpp"
#include "engine/ecs/world.hpp"
#include "procedures/scene/nucleus_removal_metrics.hpp"
#include "systems/metrics/metrics.hpp"

namespace phaco {

struct Scene;

struct DrillEvent {
  double t_s = 0;
  const char* kind = "";
  int hand = -1;                 // index into DrillRecord::hands, −1: the drill's
  const char* detail = nullptr;  // name of `value`, if any
  double value = 0;
};

struct HandRecord {
  Entity tool;
  Hand hand = Hand::Right;
  ToolKind kind = ToolKind::Forceps;
  std::vector<Vec3> pos;  // per sample (t = 0, then the end of every frame)
  std::vector<double> speed_mm_s, force_mn;
  metrics::Kinematics kinematics;
  metrics::RunningStats force;  // over the frames (not the t = 0 sample)
  // Frames in which these forceps hold the flap of an open tear (CapsuleCutting::tearing), and the
  // force over them: the tear's plateau (issue 17 item 5).
  std::vector<uint8_t> tearing;
  metrics::RunningStats tear_force;
  double tearing_s = 0;
  // Event state.
  bool closed = false, holding = false, in_lens = false, beyond_cornea = false, breach = false;
  bool entered_eye = false;
  Vec3 port = Vec3::Zero();  // where the tip first went behind the cornea: the incision
  uint64_t grasps = 0, releases = 0, missed_grasps = 0, lens_contacts = 0, iris_contacts = 0;
  uint64_t corneal_stress = 0, capsule_breaches = 0;
};

// The scene's geometry the detectors test against (DESIGN.md §6, the eye parameters).
struct Anatomy {
  HapticTool lens;                  // only its lens_* fields: lens_penetration's input
  double lens_stiffness_mn_mm = 0;  // seed 003's k_f
  double iris_z_mm = 0, pupil_radius_mm = 0, limbus_radius_mm = 0;
  Vec3 cornea_centre = Vec3::Zero();
  double cornea_posterior_radius_mm = 0;
  double port_radius_mm = 0;  // a tip this close to where it entered is in the wound
  double phaco_tip_radius_mm = 0;
  double cystotome_tip_mm = 0;
  double capsule_half_thickness_mm = 0;  // a tip this far into the lens is still in the capsule
};

struct DrillRecord {
  Anatomy anatomy;
  std::vector<HandRecord> hands;
  std::vector<double> t_s;
  std::vector<DrillEvent> events;
  size_t tear_events_seen = 0;
  size_t rim_events_seen = 0;                   // CapsuleCutting::rim's events already pushed
  std::optional<Vec3> first_grasp;              // where forceps first closed (grasp.offset_mm)
  std::optional<Vec3> puncture;                 // the cystotome's tip when it first cut the capsule
  std::optional<NucleusRemovalRecord> nucleus;  // the nucleus_removal drill's measures
};

// The scene's drill record (on its first body), or nullptr before drill_metrics_system added it.
DrillRecord* record_of(Scene& scene);

void push_event(DrillRecord& r, double t, const char* kind, int hand, const char* detail = nullptr,
                double value = 0);

}  // namespace phaco
