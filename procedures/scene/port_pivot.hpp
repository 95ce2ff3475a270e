#pragma once
// The shaft of a position-only input pivoting in its corneal port (issue 20 item 2): the mouse and
// the gamepad give a tip and no orientation, so the trainer makes one the way a surgeon holds an
// instrument in its incision — the shaft runs from the tip through the port's centre, and moving
// the tip swings the shaft about the port (docs/trainer.md, "Ports"). The shaft is the drawn one,
// its axis beside the tip by the tool's bent point (engine/io/tool_shape), not the line through
// the tip.
#include "components/eye_ports.hpp"
#include "engine/io/scenario.hpp"
#include "engine/io/track.hpp"

namespace phaco {

// `pose` with its shaft (local +z, tip → handle) turned by the least rotation that puts the
// shaft's axis of a `kind` tool through `port`'s centre, once the tip is `blend_mm` past the point
// where it begins (inside the eye): the centre, along the port's axis, for a straight tool; for a
// bent point that much deeper again as the point is long, since with the tip closer to the centre
// than its bend the axis could only pass it across the tunnel. Before, the orientation is
// `pose`'s; in between the two are blended (slerp), so the pose never jumps as the tip goes in.
// Position, grip and pedal unchanged.
ToolPose pivot_in_port(const ToolPose& pose, const EyePort& port, ToolKind kind,
                       double blend_mm = 1.0);

}  // namespace phaco
