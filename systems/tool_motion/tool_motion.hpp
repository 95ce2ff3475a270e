#pragma once
// Input phase: each scripted tool takes the pose its track gives at the end of the frame
// (linear position, grip and pedal; slerp orientation — DESIGN.md §7). A device backend will
// replace the track for the trainer; the pose component is what every later system reads.
//
// Reads: tools.track. Writes: tools.pose.
#include "components/tool.hpp"

namespace phaco::tool_motion {

inline constexpr const char* kReads[] = {"tools.track"};
inline constexpr const char* kWrites[] = {"tools.pose"};

inline void move_tool(const ToolTrack& track, ToolState& state, double t_s) {
  state = sample_track(track.samples, t_s);
}

}  // namespace phaco::tool_motion
