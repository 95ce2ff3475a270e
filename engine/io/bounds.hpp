#pragma once
// Bounds on the numbers a scenario or drill file may carry (issue 18; docs/scenario_format.md,
// "Bounds"). A number outside them is an InputError naming the file and the JSON path
// ("FILE: hands.right.track[3].pos[2]: expected ..."), never a surprise later in the run. The eye
// parameters' ranges are the eye model's (procedures/eye/eye_param_ranges.hpp).
#include <nlohmann/json.hpp>
#include <string>

#include "engine/core/math.hpp"
#include "engine/core/workspace.hpp"

namespace phaco {

// The workspace (engine/core/workspace.hpp, shared with the devices' sample bounds): every
// position a file gives (track samples, drill guidance points) lies within ±kWorkspaceHalfMm of
// the eye's origin on each axis, so every coordinate stays small enough that squares, spans and
// bounding boxes of tool paths are finite (a tool at 1e300 mm made a histogram of tool speeds,
// and a port's arc, non-finite: issue 18).
// The fixed step: 100 kHz at the finest (ten times the haptic rate), 10 Hz at the coarsest
// (coarser steps cannot resolve tool contact).
inline constexpr double kMinStepS = 1e-5;
inline constexpr double kMaxStepS = 0.1;
// The longest scenario, s; also the latest time a track sample may have.
inline constexpr double kMaxDurationS = 3600;
// Drill targets and score fall-offs, in their metrics' units (mm, degrees, mN, s, counts): every
// metric a drill reports is far below this; a larger bound is a typo, not a tolerance.
inline constexpr double kMaxMetricMagnitude = 1e6;

namespace io {
class JsonReader;

// Reads the array `v` at `path` as [x, y, z] in mm inside the workspace. Throws InputError naming
// the offending coordinate ("...pos[2]: expected a coordinate in -50..50 mm ...").
Vec3 read_workspace_point(const JsonReader& reader, const nlohmann::json& v,
                          const std::string& path);
}  // namespace io

}  // namespace phaco
