#pragma once
// A scripted capsulorhexis on the anterior capsule mesh, for tests and the perf harness (issue 4):
// the cystotome punctures the capsule at the centre and cuts radially, then diverts the cut to run
// circumferentially, making the flap (seed 000 §6.2, seed 003's L-shaped start); then the tear is
// driven round by the flap force (systems/tear) until it meets the cut it started from and the
// disc comes free; the opening is measured (opening.hpp).
//
// The pull is scripted, not simulated: the flap force has a fixed magnitude and points from the
// tear tip toward where the forceps pull. In the ideal script the surgeon regrasps near the tip
// every regrasp_every_deg and keeps the pull tangential, steering back toward the target circle in
// proportion to the tip's radial error (a tangential tear, seed 004); the outward script pulls away
// from the axis, as a trainee who does not regrasp ends up doing, so the tear runs out radially.
//
// Reads and writes: the cut mesh (particles, triangles, springs, topology).
#include <cstdint>

#include "procedures/rhexis/opening.hpp"
#include "systems/cut/progressive_cut.hpp"
#include "systems/tear/tear.hpp"

namespace phaco::rhexis {

struct RhexisScript {
  enum class Pull : uint8_t { Circular, Outward } pull = Pull::Circular;
  double radius_mm = 2.6;            // target circle (diameter 5.2)
  double flap_start_deg = 20.0;      // the cystotome's cut turns onto the circle by here
  double cystotome_sample_mm = 0.1;  // cut-point sampling along the cystotome's path
  double pull_mn = 40.0;             // flap force magnitude
  double steer_per_mm = 2.0;         // ideal pull: tangent + this × (radius error) radially
  double regrasp_every_deg = 90.0;
  double outward_angle_deg = 60.0;  // outward pull: angle of the pull from the tangent
  uint32_t max_tear_steps = 4000;
};

struct RhexisResult {
  Opening opening;
  bool tear_complete = false;  // the tear met its own start (or the rim)
  uint32_t tear_steps = 0, tear_advances = 0, regrasps = 0;
  uint32_t runout_warnings = 0, radial_tearouts = 0;
  double first_warning_radius_mm = -1.0;  // tip radius at the first warning; -1 if none
  double tearout_radius_mm = -1.0;  // tip radius when the tear left the safe zone; -1 if never
  double max_radius_mm = 0.0;
  double flap_radius_mm = 0.0;     // where the cystotome's cut ended
  double tear_step_us_mean = 0.0;  // wall time of one tear step (cut included), for the harness
  double tear_step_us_max = 0.0;
};

// Throws std::invalid_argument for a script with a non-positive radius, pull or sampling.
RhexisResult run_scripted_rhexis(cut::CutMesh& mesh, const RhexisScript& script,
                                 const tear::TearSettings& tear, const cut::CutSettings& cut);

// The surface point of the mesh straight below (x, y) along the optical axis (the highest triangle
// over it; a scan of the mesh, for scripts), or the nearest surface point if none lies over it.
Vec3 surface_below(const cut::CutMesh& mesh, double x, double y, uint32_t& hint,
                   const cut::SnapSettings& snap);

}  // namespace phaco::rhexis
