#pragma once
// The membrane's own mechanics beside the capsulorhexis front (issue 17 item 3). The drill's
// outcome (opening diameter, circularity) is drawn by the forceps' track and the tear rule, which
// every integrator shares, so an integrator can lie on that front while the membrane it moves
// does not answer a load as the tissue does. The membrane study's static-load case ("Speed
// against accuracy at the real capsule material", perf/results/membrane.json) measures exactly
// that, at the scene's own step; this reads it and says whether an integrator on the front may
// replace the default.
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "perf/sweep/sweep_data.hpp"

namespace phaco::perf {

// Per scene integrator name (implicit_euler, semi_implicit_001, xpbd, ...): the membrane study's
// relative error after one frame of a point load at `setting` (e.g. "dt 1/120 s"), and the study's
// method label it came from. XPBD is measured at 8 iterations there (the scene runs 4, which can
// only be further off). Missing file or entries: an empty map.
struct MembraneError {
  std::string method;  // the study's label, e.g. "xpbd 8 it"
  double error = 0;    // ‖u − u_ref‖ / ‖u_ref‖ against the static equilibrium
};
std::map<std::string, MembraneError> membrane_static_errors(const std::filesystem::path& file,
                                                            const std::string& setting);

// An integrator may replace the default only if its membrane error at the scene's step is at most
// this many times the default's (and the drill's front prefers it).
inline constexpr double kMechanicsTolerance = 2.0;

// A paragraph for the capsulorhexis front: each integrator alternative that is on the front or
// both faster and closer at level 3 while the default is not, with its static-load error against
// implicit Euler's, and whether it may replace the default. "" when no integrator contends.
std::string integrator_mechanics_md(const std::vector<SweepRow>& rows,
                                    const std::filesystem::path& membrane_file,
                                    const std::string& skip_variant);

}  // namespace phaco::perf
