#pragma once
// Scenario files (DESIGN.md §7): which drill, which eye, the fixed step, the seed, the duration
// and, per hand, a tool with a timed track. The same format drives tests, demos, the perf harness
// and recorded sessions, so it is validated strictly: unknown fields, unsorted tracks, non-finite
// numbers and numbers outside their bounds (engine/io/bounds.hpp, docs/scenario_format.md) are
// errors with a message "FILE: JSON.PATH: what was expected, what was found".
#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "engine/core/math.hpp"

namespace phaco {

enum class Drill : uint8_t { CornealIncision, Capsulorhexis, PhacoSculpting, NucleusRemoval };
enum class ToolKind : uint8_t {
  Forceps,
  Keratome,
  Cystotome,
  PhacoProbe,
  Hook,
  Aspirator,
  Chopper
};
enum class Hand : uint8_t { Left, Right };

std::string_view to_string(Drill drill);
std::string_view to_string(ToolKind tool);
std::string_view to_string(Hand hand);
std::optional<Drill> parse_drill(std::string_view name);
std::optional<ToolKind> parse_tool(std::string_view name);
std::optional<Hand> parse_hand(std::string_view name);

struct TrackSample {
  double t = 0;                  // s, from the start of the scenario
  Vec3 pos = Vec3::Zero();       // mm, tool tip
  Quat quat = Quat::Identity();  // unit; the shaft is the tool's local +z rotated by quat
  double grip = 0;               // 0 open .. 1 closed (forceps)
  double pedal = 0;              // 0..3 phaco foot pedal, 3 = ultrasound on
};
bool operator==(const TrackSample& a, const TrackSample& b);  // exact, component-wise

struct HandTrack {
  Hand hand = Hand::Right;
  ToolKind tool = ToolKind::Forceps;
  std::vector<TrackSample> track;  // t strictly increasing, at least one sample
  bool operator==(const HandTrack&) const = default;
};

struct EyeSpec {
  int level = 3;                               // mesh resolution level 0..8
  std::string capsule_layout = "curvilinear";  // or "isotropic"
  std::map<std::string, double> overrides;     // "section.key" -> value, checked by the eye model
  std::optional<std::filesystem::path> params_file;     // resolved, absolute
  std::map<std::string, std::filesystem::path> meshes;  // body -> OBJ file, resolved, absolute
  bool operator==(const EyeSpec&) const = default;
};

// A patient's difficulty settings (issue 7 item 1; seed 004 §1's anomalies), each optional;
// procedures/eye/difficulty turns them into eye parameters (docs/drills.md).
struct DifficultySettings {
  std::optional<double> patient_age_years;          // [1, 100]: capsule modulus and strength
  std::optional<double> anterior_bowing_kpa;        // [0, 2]: posterior (vitreous) pressure
  std::optional<double> anterior_chamber_depth_mm;  // [1.5, 4.5]: lens pole to corneal endothelium
  std::optional<double> nucleus_hardness;           // [0.05, 1]: soft .. brunescent
  bool operator==(const DifficultySettings&) const = default;
  // `over`'s present fields replace these.
  DifficultySettings overlaid(const DifficultySettings& over) const;
};

struct Scenario {
  std::string source;  // file path as given, for messages; not part of equality
  std::string name, description;
  Drill drill = Drill::Capsulorhexis;
  // Per-body method choices, "body.setting" -> name, e.g. "capsule.integrator" -> "implicit_euler";
  // the scene builder checks the names.
  std::map<std::string, std::string> methods;
  EyeSpec eye;
  // The drill file (data/drills/<drill>.json unless given, resolved and absolute) and the
  // difficulty: a level of that file ("" = its default) and explicit settings over it.
  std::optional<std::filesystem::path> drill_file;
  std::string difficulty;
  DifficultySettings difficulty_settings;
  double dt_s = 1.0 / 120.0;  // s, fixed simulation step
  uint64_t seed = 0;
  double duration_s = 0;         // s
  std::vector<HandTrack> hands;  // left first if present

  // Number of fixed steps covering the duration: ceil(duration / dt - 1e-9).
  uint64_t frame_count() const;
  // The track of `hand`, or nullptr when that hand is not scripted.
  const HandTrack* find_hand(Hand hand) const;
};
bool operator==(const Scenario& a, const Scenario& b);

namespace io {
class JsonReader;
}
// Reads the four difficulty settings from the object `v` at `path`, whose other allowed keys are
// `extra` (e.g. "level"); shared by scenarios and drill files. Throws InputError.
DifficultySettings read_difficulty_settings(const io::JsonReader& reader, const nlohmann::json& v,
                                            const std::string& path,
                                            std::initializer_list<std::string_view> extra);

// Reads, parses and validates a scenario file; relative paths inside resolve against its
// directory. Throws InputError.
Scenario load_scenario(const std::filesystem::path& file);
// Parses and validates scenario text; `source` names it in messages, `base_dir` resolves paths.
Scenario parse_scenario(std::string_view json_text, const std::string& source,
                        const std::filesystem::path& base_dir);
// The same format back, every field explicit except empty name/description and zero grip/pedal;
// parse_scenario(to_json(s).dump(), ...) == s. Recordings are written with it.
nlohmann::json to_json(const Scenario& scenario);

}  // namespace phaco
