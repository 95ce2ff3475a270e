#pragma once
// Tearing the anterior capsule (capsulorhexis): where the tear goes next, turned into cut points
// for the progressive cut (systems/cut), and the run-out warning.
//
// Two rules, selectable:
//  - FlapForce, seed 000 §6.2: once the flap force f_t projected on the membrane at the tear tip
//    exceeds a threshold, the next cut point is c_{t+1} = c_t + a·f_t + b·ĉ_t (ĉ_t the unit
//    direction of the current cut segment), snapped to nearby primitives by the cut. The seed's
//    formula gives the new point from the two vectors; we read it as the displacement from c_t,
//    capped at max_step_mm so a sudden jerk cannot jump across the mesh in one frame.
//  - MostStressedSpring, seed 001 §3.4: "breaking the spring exerting largest force on a vertex if
//    it is overextended, and propagating cuts along the most stressed directions": of the springs
//    at the tip stretched beyond break_strain, the one with the largest force breaks, and the cut
//    runs along it to its far end.
// An outward bias (anterior bowing of the lens diaphragm, positive posterior pressure: seed 004
// names both as pushing the tear peripherally) adds outward_bias·|f_t|·r̂ to the flap-force step.
//
// Seed 004's warning: "the training software alerts the user of any potential tear problems before
// they occur". Before each step the proposed tear direction is judged against the radial
// direction r̂ at the tip: turning outward by more than warn_angle_deg, or heading to cross the
// safe-zone circle (safe_radius_mm from the optical axis) within warn_lookahead_mm, raises a
// RunoutWarning — once per excursion, re-armed when the direction turns back. A tip beyond the safe
// radius is a runaway radial tear, recorded once as RadialTearout.
//
// The tear as the force limit (issue 17 item 5). Force-sensing forceps on porcine and human lenses
// show the tearing force stable while the crack runs round: the flap's tension plateaus at the
// capsule's tear resistance. We take the flap tear as a trouser tear (Rivlin & Thomas, J. Polym.
// Sci. 10:291, 1953; the flap folded over and pulled along the tear, as in a capsulorhexis): the
// energy balance F·2Δa = G_c·h·Δa for a crack advance Δa with inextensible legs gives the critical
// force
//     F_c = G_c·h / 2,
// G_c the capsule's fracture (tearing) energy, J/m² = mN/mm, h its thickness. G_c comes from the
// eye file (capsule.tear_energy_j_m2) and follows the patient's age with the modulus and the
// ultimate stress (procedures/eye/difficulty: a cohesive zone, G_c = σ_u·δ_c with a fixed critical
// opening δ_c, so G_c scales as σ_u). tear_resistance_mn gives F_c; it is the flap-force rule's
// threshold. Once the flap force reaches it, tear_until_below runs the tear — several steps in one
// frame if needed — until the force, relaxed by the advance, falls back below it: the flap, a strip
// of elongation e between the forceps and the tear's tip, loses Δ of elongation when the tear
// runs Δ toward the pull (F' = F·(1 − Δ/e)), so the tear advances about e·(1 − F_c/F) and a taut
// flap's force cannot ramp above the plateau. (In the scene the held flap also drags the disc,
// which no advance relieves: procedures/scene/capsule_cutting folds it at F_c.)
//
// The tear's last step: the ligament to its own start (issue 17). A tear that has come round to
// within w of its own earlier cut (the cystotome's slit) leaves the disc hanging by a ligament of
// width w; pulled by the flap force F, the ligament breaks once its net section reaches the
// capsule's ultimate stress: F ≥ σ_u·h·w (net-section rupture of a remaining ligament, the plastic
// collapse limit of fracture mechanics; σ_u ≈ 0.7 MPa, DESIGN §6, from the eye file; seed 001
// §3.4 breaks the mesh's springs by the same kind of criterion, over-extension). The tear then runs
// straight through the ligament to that cut and the disc is free: a real capsule does not stop
// 0.05 mm short of its own edge, where the flap-force rule would (the disc all but free, the pull
// falls to 2–4 mN, far under F_c). The pull counts up to F_c (the tension at the tip plateaus
// there; beyond it the forceps drag the disc), so physics alone would reach w ≤ F_c/(σ_u·h) =
// δ_c/2 (G_c = σ_u·δ_c, above) ≈ 1.07 mm on the standard eye. Measured without either bound (the
// pull 15.8 mN in the expert's final inward pull), the rule cut the last 1.5 mm by a chord (level
// 3: 5.24 mm instead of 5.33). So the rule is the tear's last step only:
// w at most max_step_mm, what one flap-force step crosses (a ligament the next step would cross
// at F_c). A tear still far from its
// start is held by a wide ligament and runs on by the rules above. Only the part of the path's own
// cut that the tear has come round to counts: points of its trail (TearState) at least
// kLigamentCurl times the ligament's width from the tip along the trail. A tear closing its circle
// is ~16 mm round from its slit; a tear hooking back beside its own slit (level 1, two_level,
// before the first grasp was moved: 0.87 mm along, 0.39 mm across) frees no disc, only a sliver.
//
// Reads: the cut mesh (positions, springs, topology), the path's tip and direction, the flap force.
// Writes: the cut mesh and path (through the cut), the TearState's events.
#include <cstdint>
#include <string_view>
#include <vector>

#include "systems/cut/progressive_cut.hpp"

namespace phaco::tear {

enum class TearRule : uint8_t { FlapForce, MostStressedSpring };
std::string_view to_string(TearRule r);

struct TearSettings {
  TearRule rule = TearRule::FlapForce;
  double threshold_mn = 10.0;  // |f_t| needed to tear (flap-force rule): the resistance F_c
  double a_mm_per_mn = 0.01;   // seed 000's a
  double b_mm = 0.05;          // seed 000's b
  double max_step_mm = 0.15;   // cap on one step's length
  double break_strain =
      0.29;  // over-extension that breaks a spring (elongation at break, DESIGN §6)
  double outward_bias = 0.0;        // anterior bowing: outward push per unit of |f_t| step
  double safe_radius_mm = 3.5;      // the tear must stay inside this circle about the optical axis
  double warn_angle_deg = 30.0;     // outward turn that warns
  double warn_lookahead_mm = 0.75;  // warn if heading to cross the safe circle within this
  double max_advance_mm = 1.0;      // tear_until_below: the most the tear runs in one frame,
  uint32_t max_steps = 16;          // in at most this many steps
  // σ_u·h, mN/mm: a ligament of width w to the path's own start holds σ_u·h·w (above); 0: off.
  double ligament_strength_mn_per_mm = 0.0;
};

// F_c = G_c·h/2 (trouser tear, above), mN, from the tearing energy in J/m² (= mN/mm) and the
// thickness in mm. Throws std::invalid_argument unless both are finite and positive.
double tear_resistance_mn(double tear_energy_j_m2, double thickness_mm);

struct TearEvent {
  enum Kind : uint8_t { RunoutWarning, RadialTearout, Completed } kind;
  uint64_t step;             // tear step index
  double radius_mm;          // tip distance from the optical axis
  double outward_angle_deg;  // of the tear direction, positive outward
  Vec3 at;
};
std::string_view to_string(TearEvent::Kind k);

struct TearState {
  uint64_t steps = 0;         // tear steps attempted
  uint64_t advances = 0;      // steps that moved the tear
  bool warning_armed = true;  // a new warning may be raised
  bool torn_out = false;      // a runaway radial tear happened
  bool complete = false;      // the tear met the rim or the cut it started from
  double max_radius_mm = 0.0;
  // The path as the tear has run it, for the ligament to its own start: the path's first vertex
  // (the slit's start), the tip when the tear began, then the tip after each advance (positions
  // as the edits see them: the rest shape in the scene). tear_step starts it.
  std::vector<Vec3> trail;
  Vec3 front = Vec3::Zero();  // where the flap-force rule has taken the tear (the tip follows
  bool front_valid = false;   // it when snapping lets it)
  std::vector<TearEvent> events;
  uint32_t count(TearEvent::Kind k) const;
};

// Seed 004: the outward angle of a tear direction at a tip (positive = away from the axis) and
// the distance along it to the safe circle (infinity if it does not head there).
struct RunoutCheck {
  double outward_angle_deg = 0.0;
  double distance_to_safe_edge_mm = 0.0;
  bool warn = false;
};
RunoutCheck check_runout(const Vec3& tip, const Vec3& direction, const TearSettings& s);

// Unit normal of the membrane at a vertex (area-weighted over its fan).
Vec3 vertex_normal(const cut::CutMesh& m, uint32_t v);

// Seed 000: the displacement c_{t+1} - c_t for a flap force (mN), or zero below the threshold.
Vec3 flap_force_step(const Vec3& tip, const Vec3& normal, const Vec3& c_hat, const Vec3& flap_force,
                     const TearSettings& s);

// Seed 001: the far end of the most stressed spring at `tip` stretched beyond break_strain, or
// kInvalidIndex. Springs along an opened cut (boundary edges behind the tip) are skipped.
uint32_t most_stressed_spring_end(const cut::CutMesh& m, uint32_t tip, const TearSettings& s);

// The ligament between a tear's tip and the path's own earlier cut (above): its width (the
// distance from `tip` to the nearest point of the trail, TearState::trail, that the path has come
// round to) and that point. found = false if the path has not come round.
constexpr double kLigamentCurl = 8.0;
struct Ligament {
  bool found = false;
  double width_mm = 0.0;
  Vec3 to = Vec3::Zero();
};
Ligament own_ligament(const std::vector<Vec3>& trail, const Vec3& tip);

struct TearStepReport {
  bool advanced = false;
  bool warned = false;
  bool torn_out = false;
  bool completed = false;
  bool ligament_broke = false;  // the step broke the ligament to the path's own start
  double advance_mm = 0.0;  // how far the tear front moved (flap force) or the tip (spring rule)
  cut::SegmentReport segment;
};

// One tear step from the path's tip (the path must have one: tearing continues a cut). Throws
// std::invalid_argument for a path without a tip or a non-finite force.
TearStepReport tear_step(cut::CutMesh& m, cut::CutPath& path, TearState& state,
                         const Vec3& flap_force, const TearSettings& tear,
                         const cut::CutSettings& cut, cut::EditLog& log);

// The tear as the force limit: tear steps while the flap force, relaxed by the advance so far
// (F' = F·(1 − Δ/e), e the flap's elongation, mm), stays at or above the threshold, up to
// max_steps and max_advance_mm. An elongation ≤ 0 or non-finite counts as max_step_mm (the flap's
// stretch unknown: one step's advance relaxes it). Same throws as tear_step.
struct TearRunReport {
  uint32_t steps = 0;       // tear steps taken (each advanced the front or the tip)
  double advance_mm = 0.0;  // total advance
  double force_before_mn = 0.0, force_after_mn = 0.0;  // |f| in, and as relaxed by the advance
  bool warned = false, torn_out = false, completed = false;
};
TearRunReport tear_until_below(cut::CutMesh& m, cut::CutPath& path, TearState& state,
                               const Vec3& flap_force, double elongation_mm,
                               const TearSettings& tear, const cut::CutSettings& cut,
                               cut::EditLog& log);

}  // namespace phaco::tear
