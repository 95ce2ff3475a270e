#pragma once
// A hand-held instrument: which tool in which hand, its scripted track and its pose this frame.
// Tool and hand names are the scenario vocabulary of engine/io (DESIGN.md §7).
#include <vector>

#include "engine/io/scenario.hpp"
#include "engine/io/track.hpp"

namespace phaco {

struct Tool {
  ToolKind kind = ToolKind::Forceps;
  Hand hand = Hand::Right;
};

struct ToolTrack {
  std::vector<TrackSample> samples;  // sorted by t; replaced by a device stream in the trainer
};

// Tip position (mm), shaft orientation, forceps grip 0..1, foot pedal 0..3; set by the input phase.
using ToolState = ToolPose;

}  // namespace phaco
