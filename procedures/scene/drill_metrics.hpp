#pragma once
// What a trainee did in a drill, measured (issue 7 item 3; seed 000 §6, seed 003 §IV.B, seed 004
// §3): a Metrics-phase system added to every scene that samples, each frame and per hand, the tool
// tip's position, speed and contact force and detects events; and, at the end of the run, the
// drill's metrics (flat, units in the names), their targets, the events, the series for plots and
// the 0–100 score with its per-term breakdown (docs/metrics.md, docs/scoring.md).
//
// Per frame, per hand (systems/metrics does the arithmetic):
//   position   the tip at the end of the frame; path length and speed |Δp|/dt from it;
//   force      forceps holding the capsule: |Σ spring forces on the held particle| (the flap's
//   pull,
//              mN); else a tip inside the lens's two half-ellipsoids: seed 003's k_f·d, k_f =
//              haptic_model.lens_stiffness_mn_mm, d the depth (systems/haptic_model
//              lens_penetration); else 0;
//   tearing    the forceps hold the flap of an open tear (CapsuleCutting::tearing): the force over
//              these frames gives <hand>.tear_force_mN.rms/mean/max and <hand>.tearing_s, and the
//              series a 0/1 "tearing" per sample (issue 17 item 5: the tear's plateau);
//   events     grasp / release / missed_grasp (the forceps' capsule grasp state), lens_contact (the
//              tip entering the lens's half-ellipsoids), iris_contact (the tip's path crossing the
//              iris plane z = iris.z_mm outside the pupil), corneal_stress (the tip beyond the
//              cornea's posterior sphere, inside the limbus, away from where it entered the eye —
//              an approximation: the scene has no wound to test against), capsule_breach (the phaco
//              tip's sphere reaching the posterior lens surface); and, from the capsule's tear,
//              runout_warning, radial_tearout, tear_complete.
// The system only reads the simulation: the state hash is the same with or without it.
//
// Reads: tools.pose, tools.grasp, capsule.particles, capsule.springs, capsule.settings,
// capsule.cutting, lens.tets, tools.ports. Writes: metrics
// (its own record, kept on the scene's first body: the scene has no drill entity). Per frame it
// appends to vectors reserved for the scenario's frame count (no allocation in a normal run).
#include <cstddef>
#include <nlohmann/json.hpp>

#include "engine/schedule/system.hpp"

namespace phaco {

struct Scene;

// Adds the record (sampling the tools' poses at t = 0) and returns the frame's system.
SystemDesc drill_metrics_system(Scene& scene);

struct DrillReport {
  nlohmann::json metrics = nlohmann::json::object();  // name → number
  nlohmann::json targets = nlohmann::json::object();  // name → {"min": a, "max": b}
  nlohmann::json events = nlohmann::json::array();    // {"t_s", "kind", "hand"?, ...} by time
  nlohmann::json series = nlohmann::json::object();   // t_s, hands, rhexis, trench
  nlohmann::json score_terms =
      nlohmann::json::array();  // {"metric", "value", "target", "weight", "points"}
  double score = 0;             // 0..100: Σ points, 0 if not attempted, capped by a complication
  bool attempted = true;        // the drill file's attempted_if_any (docs/scoring.md)
  nlohmann::json complications =
      nlohmann::json::array();  // {"name", "metric", "value", "score_cap"}: the drill failed
};

// The drill's report so far (call at the end of the run); empty if the scene has no record.
DrillReport drill_report(Scene& scene);

// One score term (docs/scoring.md): `weight` points inside [min, max] (either bound may be absent),
// falling linearly to 0 at `falloff` outside the band; a missing value (e.g. the diameter of an
// opening that never closed) scores 0.
double band_points(const nlohmann::json& value, const nlohmann::json& target, double falloff,
                   double weight);

// The trainer's live warnings (procedures/trainer): the events recorded so far, in time order,
// read on the simulation thread between frames. `kind` and `detail` are string literals (static
// storage), so an event may be handed to another thread as is. hand: the Hand's index, −1 for the
// drill's own events.
struct LiveDrillEvent {
  double t_s = 0;
  const char* kind = "";
  int hand = -1;
  const char* detail = nullptr;  // name of `value`, if any
  double value = 0;
};
size_t drill_event_count(Scene& scene);
LiveDrillEvent drill_event(Scene& scene, size_t index);  // index < drill_event_count

}  // namespace phaco
