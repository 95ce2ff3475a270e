#pragma once
// The mouse as a clutched haptic device (issue 24 item 1): the pointer drives the selected tool
// only while it is over the microscope view. Over a panel, outside the window, or with the clutch
// key held (middle button or Shift), the tools stay where they are and the pointer moves freely;
// back in the view, motion resumes relative to the tool's pose, so the tool never jumps.
#include <array>

namespace phaco {

struct PointerClutch {
  bool have_last = false;
  bool engaged_last = false;  // the last position was in the view with the clutch released
  double last_x = 0, last_y = 0;
};

// One UI frame with the pointer at (x, y) px. `in_view`: the pointer is inside the window and over
// no panel; `held`: the clutch key is down. Returns the pointer motion (px) the tool follows: zero
// unless this position and the last are both engaged.
std::array<double, 2> clutch_step(PointerClutch& c, double x, double y, bool in_view, bool held);

}  // namespace phaco
