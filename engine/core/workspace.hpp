#pragma once
// The workspace every position lives in (issue 18 item 1): a box of ±kWorkspaceHalfMm around the
// eye's origin on each axis, scene frame. The eye is ~24 mm across and the tools reach it through
// incisions a few mm outside the limbus, so 50 mm leaves room for any real hand movement while a
// position beyond it can only be a fault (a corrupt packet, a tracker that lost the hand, a
// mistyped track). Device samples outside it are dropped (engine/haptics/sample_bounds.hpp).
namespace phaco {

inline constexpr double kWorkspaceHalfMm = 50.0;  // mm, per axis, from the eye's origin

}  // namespace phaco
