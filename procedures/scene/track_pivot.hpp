#pragma once
// Scripted tracks in a carried main port (issue 20 item 1, docs/procedures.md "The carried port").
// A drill's scripted track is made for the drill's default main port; in a procedure the main port
// is the incision the trainee cut, elsewhere and at another angle (the expert's: 4.46 mm from the
// axis rising 14.8° inward, the default 5.5 mm falling 15°), and a shaft aimed at the default port
// presses on the real tunnel (the expert's rhexis: 112 mN, the globe turned 4.6°). So the scene
// moves such a track into the cut port, every frame, before the ports measure:
//   - near the port (the tip outside the eye, in the tunnel, or a little past the default port's
//     centre) the tip and shaft are carried rigidly from the default port onto the cut one, so
//     the tool enters and leaves through the cut tunnel;
//   - deeper, the tip is the track's (the work inside the eye unchanged), the shaft re-aimed
//     through the cut port's centre as a surgeon's hand does (port_pivot); in between, blended.
//
// Which hands: the main-port hand (the right, the scripted drills' convention; not a keratome,
// which cuts its port), when the scene has a carried main port and its ports "measure" (scripted,
// track and replay inputs). Live inputs run in "constrain", where the solver holds the tool in
// the port itself and the desktop pivots its own (procedures/trainer/live_ports); their
// recordings say "constrain", so a replay is not moved twice. A drill on a fresh eye is
// unchanged: no carried port, nothing moved.
#include <array>
#include <optional>

#include "components/eye_ports.hpp"
#include "components/tool.hpp"

namespace phaco {

struct Scene;

// A track made for port `from`, played through port `to`.
// Carried whole until the tip is `carried_mm` past `from`'s centre, then blended to the track's
// own tip over `blend_mm` more; the shaft runs through `to`'s centre from `aim_mm` past it. So a
// track that enters along `from`'s axis stays on `to`'s tunnel line until it is past its centre,
// and past it the shaft goes through the centre, however the tip blends.
struct TrackPivot {
  EyePort from, to;
  ToolKind tool = ToolKind::PhacoProbe;  // whose shaft is aimed (a bent point's axis)
  double carried_mm = 0.5, blend_mm = 2.0, aim_mm = 0.5;
};

// Per hand, indexed as Hand (none: the track as it is).
std::array<std::optional<TrackPivot>, 2> track_pivots(const Scene& scene);

// `pose` moved from the pivot's default port into its carried one (above).
ToolState pivot_track(const ToolState& pose, const TrackPivot& pivot);
void pivot_track_pose(ToolState& pose, const std::optional<TrackPivot>& pivot);

}  // namespace phaco
