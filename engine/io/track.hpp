#pragma once
// Sampling a scripted tool track at simulation time t. Called every frame for every scripted
// hand, so it neither allocates nor throws.
#include <span>

#include "engine/core/math.hpp"
#include "engine/io/scenario.hpp"

namespace phaco {

struct ToolPose {
  Vec3 pos = Vec3::Zero();       // mm, tool tip
  Quat quat = Quat::Identity();  // unit
  double grip = 0;               // 0..1
  double pedal = 0;              // 0..3
};

// Pose at time t: pos, grip and pedal interpolate linearly, quat by slerp along the shorter arc.
// Before the first sample and after the last the end sample is held. Exact at sample times.
// Binary search, O(log n). An empty track gives the default pose (origin, identity, open, off).
ToolPose sample_track(std::span<const TrackSample> track, double t);

// Spherical linear interpolation from a (u = 0) to b (u = 1) along the shorter arc; unit result.
Quat slerp_shortest(const Quat& a, const Quat& b, double u);

}  // namespace phaco
