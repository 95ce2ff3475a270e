#pragma once
// A tool pressing on the rhexis rim in the steps after the capsulorhexis (issue 20 item 1): "a
// probe that hits a small or torn rim can extend the tear", and a radial tear that runs to the
// equator fails the procedure.
//
// The tools do not push the capsule in these scenes (its dynamics move only what forceps hold),
// so the press is measured on the capsule as it lies, not simulated:
//
//            tool shaft (radius r)
//                 \ \ .
//   opening        \ \ P        membrane →           P where the shaft leaves the lens through
//   ────────────────●──\──────────────────           its anterior surface (the capsule lies on
//                  rim  s = ±|P − rim|                it), s its distance from the nearest rim
//                                                     point, + into the membrane, − in the opening
//
// The tool's section reaches δ = r + s past the rim: the tool has pushed the rim that far out, and
// the stretched rim pushes back F = k·δ (k: capsule.rim_stiffness_mn_mm, the secant stiffness of
// a CCC rim stretched to rupture). The rim is the capsule's free edges between free particles (the
// outer rim, held by the zonules, is anchored): the opening's edge and the lips of any tear.
//
// A smooth rim tears once F reaches capsule.rim_strength_mn (a finished CCC rim, 150 ± 70 mN,
// porcine). A rim with a notch — a rim vertex within the tool's diameter of the contact round which
// the membrane turns by more than notch_angle_deg (the tip of a nick, of an incomplete rhexis or of
// an earlier tear) — is a tear already begun: it runs at the tear resistance F_c = G_c·h/2, the
// force at which systems/tear runs an existing tear. The tear starts at the notch's tip (a point
// of irregularity on a capsulotomy rim is where its tear starts), else at the rim vertex nearest
// the contact, and runs outward along the push by seed 000's rule (tear_until_below), until the
// stretch the tool gave the rim is spent: the rim a strip of elongation δ relaxed by the tear's
// advance A, F = k·(δ_max − A), so a push of δ_max runs the tear δ_max − F_c/k. A tool pushing on
// drives its tear further; withdrawn (δ ≤ 0), it leaves the tear's tip as a notch on the rim.
// A tear whose tip reaches the capsule's outer radius (less equator_margin_mm) is a radial tear to
// the equator: the drills' complication `rim.tears_to_equator`.
//
// A drill alone has no opening (its capsule is whole): no rim, nothing happens; in a procedure the
// carried capsule has the opening the trainee tore.
//
// Reads: tools.pose, the capsule's cut mesh. Writes: the capsule's cut mesh (through the tear), the
// RimTears state. Runs inside capsule_cut (procedures/scene/capsule_cutting), which owns the edit.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <vector>

#include "systems/cut/progressive_cut.hpp"
#include "systems/tear/tear.hpp"

namespace phaco {

struct Scene;
struct CapsuleCutting;

struct RimTearSettings {
  double stiffness_mn_mm = 67.0;      // k (capsule.rim_stiffness_mn_mm)
  double smooth_strength_mn = 150.0;  // a smooth rim (capsule.rim_strength_mn)
  double notched_strength_mn = 9.75;  // a notched rim: the tear resistance F_c
  double notch_angle_deg = 270.0;     // the membrane's angle round a notch's tip exceeds this
  double shaft_mm = 12.0;             // the length of shaft from the tip that can press
  double outer_radius_mm = 4.5;       // the capsule's outer rim (capsule.radius_mm)
  // The anterior capsule's surface: the lens's anterior half-ellipsoid (semi-axes R, R, c).
  double lens_radius_mm = 4.7, lens_anterior_mm = 1.8;
  double equator_margin_mm = 0.1;
};

// A free edge of the capsule between two free particles, its triangle, and the membrane's normal
// there (the mean of its ends' area-weighted normals: a sliver's own normal is noise).
struct RimEdge {
  uint32_t a = 0, b = 0, triangle = 0;
  Vec3 normal = Vec3::UnitZ();
};

// One tool's press on the rim.
struct RimPress {
  bool crossing = false;        // the shaft crosses the membrane's plane at a rim edge
  double depth_mm = 0.0;        // δ; negative: the clearance to the rim
  Vec3 at = Vec3::Zero();       // the rim point pressed
  Vec3 outward = Vec3::Zero();  // unit, in the membrane's plane, into the membrane
  Vec3 normal = Vec3::Zero();   // the membrane's unit normal there
  uint32_t vertex = 0;          // the rim vertex nearest `at`
};

struct RimTear {
  size_t tool = 0;       // the scene tool that started it
  bool driven = true;    // that tool still presses it
  bool notched = false;  // it started at a notch
  double time_s = 0.0;   // when it started
  double start_force_mn = 0.0;
  uint32_t start_vertex = 0;  // the rim vertex (or notch tip) it starts from, at `origin`
  Vec3 origin = Vec3::Zero();
  // The rim point the tool pressed, the push's direction and the membrane's normal there: the
  // tool's push on its tear is measured from that point along that direction.
  Vec3 pressed = Vec3::Zero(), outward = Vec3::Zero(), normal = Vec3::Zero();
  double pushed_mm = 0.0;   // the deepest push δ_max
  double advance_mm = 0.0;  // the tear's advance A
  double length_mm = 0.0;   // from the origin to the tip
  bool to_equator = false;
  cut::CutPath path;
  tear::TearState state;
};

struct RimTearEvent {
  double t_s = 0.0;
  const char* kind = "";  // "rim_tear", "rim_tear_to_equator"
  size_t tool = 0;
  const char* detail = "";
  double value = 0.0;
};

struct RimTears {
  RimTearSettings settings;
  std::vector<double> tool_radius_mm;  // per scene tool; 0: the tool does not press
  std::vector<RimEdge> rim;
  uint64_t rim_version = ~uint64_t{0};  // CapsuleCutting::topology_changes the rim was taken at
  std::vector<RimTear> tears;
  std::vector<RimTearEvent> events;
  std::vector<RimPress> presses;  // this frame's, per scene tool
  std::vector<uint32_t> pending;  // tears to run in this frame's edit (indices)
  // Over the run.
  double max_force_mn = 0.0;
  std::vector<double> tool_max_force_mn;  // per scene tool
  double min_clearance_mm = 1e9;          // the closest a crossing tool's section came to the rim
  uint64_t pressing_frames = 0;           // frames in which a tool pressed the rim (δ > 0)
  uint32_t to_equator = 0;
};

// The capsule's rim (RimEdge above), in triangle order.
std::vector<RimEdge> rim_edges(const cut::CutMesh& m);

// Where the shaft (from `tip` along the unit `shaft` for s.shaft_mm) leaves the lens through its
// anterior surface, if it does (the tip inside the lens, the crossing above the equator).
std::optional<Vec3> capsule_crossing(const Vec3& tip, const Vec3& shaft, const RimTearSettings& s);

// A tool's press on the rim: from that crossing to the nearest rim point (none: no crossing).
RimPress rim_press(const cut::CutMesh& m, std::span<const RimEdge> rim, const Vec3& tip,
                   const Vec3& shaft, double radius_mm, const RimTearSettings& s);

// The angle the membrane turns round vertex v (the sum of its triangles' angles there), degrees:
// 360 inside, about 180 on a smooth rim, more at a notch's tip.
double membrane_angle_deg(const cut::CutMesh& m, uint32_t v);

// Set-up from the scene's parameters and tools (in add_capsule_cutting).
RimTears make_rim_tears(const Scene& scene, double tear_resistance_mn);

// The frame's presses, on the capsule as it lies: records the forces, starts tears where a press
// exceeds the rim's strength and lists the tears to run (rim.pending). Returns whether any runs.
bool press_rim(Scene& scene, cut::CutMesh& m, CapsuleCutting& cc, double time_s);

// Runs the pending tears (in the capsule's rest shape, inside capsule_cut's edit).
void run_rim_tears(cut::CutMesh& m, CapsuleCutting& cc, double time_s);

// rim.notches, rim.max_force_mN (and .left / .right per hand), rim.clearance_mm.min,
// rim.pressing_frames, rim.tears, rim.tears_to_equator, rim.tear_length_mm.max, for a scene whose
// capsule has a rim (an opening) and a tool that can press it; nothing otherwise.
void rim_metrics(Scene& scene, nlohmann::json& metrics);

}  // namespace phaco
