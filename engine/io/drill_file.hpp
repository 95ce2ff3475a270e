#pragma once
// Drill files (issue 7 item 1; data/drills/*.json, docs/drills.md): what a drill is, as data — the
// scene it needs (which bodies), the tools each hand may hold, its targets and tolerances
// (DESIGN.md §6), how it is scored (docs/scoring.md), the guidance cues drawn for the trainee
// (seed 000 Fig. 8: optimal grasp and puncture sites, the target rhexis circle, the trench cross,
// the incision site) and its difficulty levels, each a set of patient settings (seed 004 §1's
// anomalies: patient age, anterior bowing of the lens diaphragm, a shallow anterior chamber; and
// nucleus hardness) that procedures/eye/difficulty turns into eye parameters.
//
// Validated as strictly as scenarios: unknown fields, unknown metrics in the scoring, a scored
// metric without a target, weights not summing to 100, out-of-range settings are errors naming
// the file and the JSON path ("capsulorhexis.json: scoring[2].weight: expected ...").
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "engine/core/math.hpp"
#include "engine/io/scenario.hpp"

namespace phaco {

// A target band: a metric meets it when min <= value <= max (either bound may be absent).
struct TargetBand {
  std::optional<double> min, max;
  bool operator==(const TargetBand&) const = default;
};

// One score term (docs/scoring.md): `weight` points inside the target band, falling linearly to 0
// at `falloff` outside it.
struct ScoreTerm {
  std::string metric;
  double weight = 0;
  double falloff = 0;
  bool operator==(const ScoreTerm&) const = default;
};

// A complication (docs/scoring.md): when `metric` is above `above`, the drill fails, named `name`,
// and its score is capped at `score_cap`.
struct Complication {
  std::string metric, name;
  double above = 0;
  double score_cap = 0;
  bool operator==(const Complication&) const = default;
};

// Guidance cues (seed 000 Fig. 8), in the eye frame (DESIGN.md §6), mm. Absent: not drawn/scored.
struct Guidance {
  std::optional<Vec3> grasp_site_mm;     // where the forceps should first close
  std::optional<Vec3> puncture_site_mm;  // where the cystotome should first cut the capsule
  struct Circle {
    Vec3 centre_mm = Vec3::Zero();  // z ignored: the circle is seen from above
    double diameter_mm = 0;
    bool operator==(const Circle&) const = default;
  };
  std::optional<Circle> rhexis_circle;
  struct Cross {
    Vec3 centre_mm = Vec3::Zero();
    double first_angle_deg = 0;  // direction of the first trench from +x, counter-clockwise
    double arm_length_mm = 0;    // centre to the end of each arm
    bool operator==(const Cross&) const = default;
  };
  std::optional<Cross> trench_cross;
  struct Site {
    double clock_hour = 0;          // as the surgeon sees the eye: 12 superior (+y), 3 at +x
    double limbus_distance_mm = 0;  // inside the limbus
    bool operator==(const Site&) const = default;
  };
  std::optional<Site> incision_site;  // the main port
  std::optional<Site> side_port;
  bool operator==(const Guidance&) const = default;
};

struct DrillFile {
  std::string source;  // file, for messages
  Drill drill = Drill::Capsulorhexis;
  std::string title, description;
  std::vector<std::string> bodies;  // scene bodies, e.g. "cornea", "capsule", "lens" (tetrahedra)
  std::vector<ToolKind> left_tools, right_tools;  // what each hand may hold
  std::map<std::string, TargetBand> targets;      // metric name → band
  std::vector<ScoreTerm> scoring;                 // weights sum to 100
  // The step was attempted when any of these metrics is > 0; a step not attempted scores 0
  // (docs/scoring.md). Empty: always attempted.
  std::vector<std::string> attempted_if_any;
  std::vector<Complication> complications;
  Guidance guidance;
  std::map<std::string, DifficultySettings> difficulty;  // level name → settings
  std::string default_difficulty;                        // a key of `difficulty`
  // The corneal ports' mode when the scenario's methods["tools.ports"] does not say
  // (procedures/scene/tool_ports, docs/tool_eye_interaction.md): "off", "measure", "constrain".
  std::string ports = "off";
};

// Body names a drill's scene may list, in the scene's creation order.
std::span<const std::string_view> drill_body_names();

// Reads and validates a drill file. Throws InputError "FILE: PATH: problem".
DrillFile load_drill_file(const std::filesystem::path& file);
DrillFile parse_drill_file(std::string_view json_text, const std::string& source);

// The settings of `level` ("" = the drill's default) with the scenario's explicit settings laid
// over them. Throws InputError naming `source` and the unknown level.
DifficultySettings resolve_difficulty(const DrillFile& drill, const std::string& level,
                                      const DifficultySettings& explicit_settings,
                                      const std::string& source);

}  // namespace phaco
