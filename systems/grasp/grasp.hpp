#pragma once
// Forceps grasp of a membrane at a vertex (seed 001 §3.4: a grasped particle becomes "scripted",
// its position imposed by the tool). Closing the forceps (grip rising past `close_at`) takes the
// nearest free particle within `radius_mm` of the tip; opening (grip below `open_at`, lower than
// close_at so a hesitant hand does not flicker) lets it go free again with the tool's velocity.
// Grasping inside a triangle or on an edge (a temporary vertex, seed 000 Fig. 9) comes with
// cutting and tearing (issue 4).
//
// Reads: tools.pose. Writes: <body>.particles (kind, position and velocity of the grasped one).
#include <cstdint>

#include "components/particles.hpp"
#include "engine/core/handle.hpp"
#include "engine/core/math.hpp"

namespace phaco::grasp {

struct GraspSettings {
  double radius_mm = 0.3;
  double close_at = 0.5;
  double open_at = 0.3;
};

// Per tool, per body: which particle the forceps hold.
struct GraspState {
  uint32_t particle = kInvalidIndex;
  bool closed = false;  // grip state after hysteresis
  bool holding() const { return particle != kInvalidIndex; }
};

// Nearest particle of the given kind within radius of `tip`, or kInvalidIndex (lowest index on
// ties).
uint32_t nearest_particle(const Particles& p, const Vec3& tip, double radius_mm,
                          ParticleKind kind = ParticleKind::Free);

// Events of one update, for metrics (regrasps) and tests.
struct GraspEvent {
  bool grasped = false;
  bool released = false;
  bool missed = false;  // closed with nothing in reach
};

// Applies the grip to the body for one frame ending at the tool pose `tip`: grasp, hold (moves the
// particle to the tip with velocity (tip − previous)/dt), or release.
GraspEvent update_grasp(GraspState& state, Particles& p, const Vec3& tip, double grip, double dt_s,
                        const GraspSettings& settings = {});

}  // namespace phaco::grasp
