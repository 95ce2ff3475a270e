#pragma once
// The shaft of a position-only input pivoting in its corneal port (issue 20 item 2): the mouse and
// the gamepad give a tip and no orientation, so the trainer makes one the way a surgeon holds an
// instrument in its incision — the shaft runs from the tip through the port's centre, and moving
// the tip swings the shaft about the port (docs/trainer.md, "Ports").
#include "components/eye_ports.hpp"
#include "engine/io/track.hpp"

namespace phaco {

// `pose` with its shaft (local +z, tip → handle) turned by the least rotation to run from the tip
// through `port`'s centre, once the tip is `blend_mm` or more past that centre along the port's
// axis (inside the eye). Before the centre the orientation is `pose`'s; in between the two are
// blended (slerp), so the pose never jumps as the tip goes in. Position, grip and pedal unchanged.
ToolPose pivot_in_port(const ToolPose& pose, const EyePort& port, double blend_mm = 1.0);

}  // namespace phaco
