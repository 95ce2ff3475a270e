#include "engine/io/scenario.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <iterator>
#include <system_error>

#include "engine/core/error.hpp"
#include "engine/io/bounds.hpp"
#include "engine/io/json_reader.hpp"

namespace phaco {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

using io::format_number;
using io::is_identifier;
using io::JsonReader;
using io::path_index;
using io::path_key;

// Names in enum order: the enum value is the index.
constexpr std::array<std::string_view, 4> kDrillNames{"corneal_incision", "capsulorhexis",
                                                      "phaco_sculpting", "nucleus_removal"};
constexpr std::array<std::string_view, 7> kToolNames{
    "forceps", "keratome", "cystotome", "phaco_probe", "hook", "aspirator", "chopper"};
constexpr std::array<std::string_view, 2> kHandNames{"left", "right"};
constexpr std::array<std::string_view, 2> kCapsuleLayouts{"curvilinear", "isotropic"};
constexpr std::array<std::string_view, 5> kMeshBodies{"cornea", "capsule", "iris", "globe",
                                                      "lens_surface"};

constexpr int kMaxLevel = 8;
constexpr double kMaxGrip = 1.0;
constexpr double kMaxPedal = 3.0;
constexpr double kMinQuatLength = 1e-9;
// A quaternion within this of unit length is kept as is, so that normalising on load is
// idempotent and a written scenario reads back bit for bit.
constexpr double kUnitTolerance = 1e-13;

template <std::size_t N>
std::optional<std::size_t> index_of(const std::array<std::string_view, N>& names,
                                    std::string_view name) {
  for (std::size_t i = 0; i < N; ++i) {
    if (names[i] == name) return i;
  }
  return std::nullopt;
}

// "section.key" with both parts identifiers.
bool is_override_key(std::string_view key) {
  const std::size_t dot = key.find('.');
  return dot != std::string_view::npos && is_identifier(key.substr(0, dot)) &&
         is_identifier(key.substr(dot + 1));
}

class ScenarioParser {
 public:
  ScenarioParser(const std::string& source, const fs::path& base_dir)
      : r_(source), base_dir_(base_dir) {}

  Scenario parse(const json& root) {
    if (!root.is_object()) {
      r_.fail("$", "expected a JSON object at the top level, got " + io::describe_value(root));
    }
    r_.expect_object(root, "$",
                     {"name", "description", "drill", "drill_file", "difficulty", "eye", "methods",
                      "dt_s", "seed", "duration_s", "hands"});
    Scenario s;
    s.source = r_.source();
    if (const json* v = JsonReader::find(root, "name")) s.name = r_.string(*v, "name");
    if (const json* v = JsonReader::find(root, "description")) {
      s.description = r_.string(*v, "description");
    }
    s.drill = static_cast<Drill>(
        choice(r_.require(root, "$", "drill", one_of(kDrillNames)), "drill", kDrillNames, "drill"));
    if (const json* v = JsonReader::find(root, "drill_file")) {
      s.drill_file = existing_file(*v, "drill_file", "drill file");
    }
    if (const json* v = JsonReader::find(root, "difficulty")) difficulty(*v, s);
    if (const json* v = JsonReader::find(root, "eye")) s.eye = eye(*v, "eye");
    if (const json* v = JsonReader::find(root, "methods")) s.methods = methods(*v, "methods");

    if (const json* v = JsonReader::find(root, "dt_s")) {
      s.dt_s = r_.number(*v, "dt_s");
      if (!(s.dt_s >= kMinStepS && s.dt_s <= kMaxStepS)) {
        r_.fail("dt_s", "expected a time step in " + format_number(kMinStepS) + ".." +
                            format_number(kMaxStepS) + " s, got " + format_number(s.dt_s));
      }
    }
    if (const json* v = JsonReader::find(root, "seed")) s.seed = r_.unsigned_integer(*v, "seed");

    const std::string duration_expected =
        "a duration > 0 and <= " + format_number(kMaxDurationS) + " s";
    s.duration_s = r_.number(r_.require(root, "$", "duration_s", duration_expected), "duration_s");
    if (!(s.duration_s > 0 && s.duration_s <= kMaxDurationS)) {
      r_.fail("duration_s",
              "expected " + duration_expected + ", got " + format_number(s.duration_s));
    }
    if (s.dt_s > s.duration_s) {
      r_.fail("dt_s", "time step " + format_number(s.dt_s) + " s is longer than duration_s " +
                          format_number(s.duration_s) + " s");
    }

    hands(r_.require(root, "$", "hands", "an object with a \"left\" and/or \"right\" hand"), s);
    return s;
  }

 private:
  template <std::size_t N>
  static std::string one_of(const std::array<std::string_view, N>& names) {
    return "one of: " + io::join_names(names);
  }

  // Index of the string `value` in `names`; `what` names the kind in "unknown drill 'x'".
  template <std::size_t N>
  std::size_t choice(const json& value, std::string_view path,
                     const std::array<std::string_view, N>& names, std::string_view what) const {
    if (!value.is_string()) {
      r_.fail(path, "expected a " + std::string(what) + " name (" + one_of(names) + "), got " +
                        io::describe_value(value));
    }
    const auto& name = value.get_ref<const std::string&>();
    const auto index = index_of(names, name);
    if (!index) {
      r_.fail(path, "unknown " + std::string(what) + " '" + name + "'; expected " + one_of(names));
    }
    return *index;
  }

  // "body.setting": "choice" — which method a body uses; names are checked by the scene builder.
  std::map<std::string, std::string> methods(const json& v, const std::string& path) const {
    if (!v.is_object()) {
      r_.fail(path,
              "expected an object of \"body.setting\": \"choice\" (e.g. \"capsule.integrator\": "
              "\"implicit_euler\"), got " +
                  io::describe_value(v));
    }
    std::map<std::string, std::string> out;
    for (const auto& [key, value] : v.items()) {
      const std::string kpath = path_key(path, key);
      if (!is_override_key(key)) {
        r_.fail(kpath,
                "method key must have the form 'body.setting' (e.g. 'capsule.integrator'), got '" +
                    key + "'");
      }
      out[key] = r_.string(value, kpath);
    }
    return out;
  }

  // "difficulty": "hard" (a level of the drill file) or {"level"?: "hard", "patient_age_years": 85,
  // ...}.
  void difficulty(const json& v, Scenario& s) const {
    if (v.is_string()) {
      s.difficulty = r_.string(v, "difficulty");
      if (s.difficulty.empty()) r_.fail("difficulty", "expected a level name, got an empty string");
      return;
    }
    s.difficulty_settings = read_difficulty_settings(r_, v, "difficulty", {"level"});
    if (const json* level = JsonReader::find(v, "level")) {
      s.difficulty = r_.string(*level, "difficulty.level");
      if (s.difficulty.empty()) {
        r_.fail("difficulty.level", "expected a level name, got an empty string");
      }
    }
  }

  EyeSpec eye(const json& v, const std::string& path) const {
    r_.expect_object(v, path, {"level", "capsule_layout", "overrides", "params", "meshes"});
    EyeSpec e;
    if (const json* level = JsonReader::find(v, "level")) {
      e.level = static_cast<int>(r_.integer_in(*level, path_key(path, "level"), 0, kMaxLevel));
    }
    if (const json* layout = JsonReader::find(v, "capsule_layout")) {
      e.capsule_layout = kCapsuleLayouts[choice(*layout, path_key(path, "capsule_layout"),
                                                kCapsuleLayouts, "capsule layout")];
    }
    if (const json* overrides = JsonReader::find(v, "overrides")) {
      const std::string opath = path_key(path, "overrides");
      if (!overrides->is_object()) {
        r_.fail(opath, "expected an object of \"section.key\": number, got " +
                           io::describe_value(*overrides));
      }
      for (const auto& [key, value] : overrides->items()) {
        const std::string kpath = path_key(opath, key);
        if (!is_override_key(key)) {
          r_.fail(kpath,
                  "override key must have the form 'section.key' (e.g. "
                  "'capsule.youngs_modulus_kpa'), got '" +
                      key + "'");
        }
        e.overrides[key] = r_.number(value, kpath);
      }
    }
    if (const json* params = JsonReader::find(v, "params")) {
      e.params_file = existing_file(*params, path_key(path, "params"), "eye parameter file");
    }
    if (const json* meshes = JsonReader::find(v, "meshes")) {
      const std::string mpath = path_key(path, "meshes");
      r_.expect_object(
          *meshes, mpath,
          {kMeshBodies[0], kMeshBodies[1], kMeshBodies[2], kMeshBodies[3], kMeshBodies[4]});
      for (const auto& [body, file] : meshes->items()) {
        e.meshes[body] = existing_file(file, path_key(mpath, body), "mesh file");
      }
    }
    return e;
  }

  // A path string relative to the scenario's directory (or absolute) naming a regular file.
  fs::path existing_file(const json& v, const std::string& path, const std::string& what) const {
    const std::string text = r_.string(v, path);
    if (text.empty()) r_.fail(path, "expected a path to the " + what + ", got an empty string");
    const fs::path given(text);
    const fs::path resolved =
        fs::absolute(given.is_absolute() ? given : base_dir_ / given).lexically_normal();
    std::error_code ec;
    const fs::file_status st = fs::status(resolved, ec);
    if (!fs::exists(st)) r_.fail(path, what + " not found: " + resolved.string());
    if (fs::is_directory(st)) {
      r_.fail(path, what + " is a directory, expected a regular file: " + resolved.string());
    }
    if (!fs::is_regular_file(st)) {
      r_.fail(path, what + " is not a regular file: " + resolved.string());
    }
    return resolved;
  }

  void hands(const json& v, Scenario& s) const {
    if (!v.is_object()) {
      r_.fail("hands", "expected an object with a \"left\" and/or \"right\" hand, got " +
                           io::describe_value(v));
    }
    if (v.empty()) {
      r_.fail("hands", "expected at least one hand (\"left\" or \"right\"), got an empty object");
    }
    for (const auto& [name, unused] : v.items()) {
      if (!index_of(kHandNames, name)) {
        r_.fail(path_key("hands", name),
                "unknown hand '" + name + "'; expected " + one_of(kHandNames));
      }
    }
    for (std::size_t i = 0; i < kHandNames.size(); ++i) {  // left first
      if (const json* h = JsonReader::find(v, kHandNames[i])) {
        s.hands.push_back(hand(static_cast<Hand>(i), *h, path_key("hands", kHandNames[i])));
      }
    }
  }

  HandTrack hand(Hand which, const json& v, const std::string& path) const {
    r_.expect_object(v, path, {"tool", "track"});
    HandTrack h;
    h.hand = which;
    h.tool = static_cast<ToolKind>(choice(r_.require(v, path, "tool", one_of(kToolNames)),
                                          path_key(path, "tool"), kToolNames, "tool"));
    const std::string tpath = path_key(path, "track");
    const json& track =
        r_.array(r_.require(v, path, "track",
                            "an array of samples {\"t\", \"pos\", \"quat\", \"grip\", \"pedal\"}"),
                 tpath, "track samples");
    if (track.empty()) r_.fail(tpath, "expected at least one track sample, got an empty array");
    h.track.reserve(track.size());
    for (std::size_t i = 0; i < track.size(); ++i) {
      h.track.push_back(sample(track[i], path_index(tpath, i), i > 0 ? &h.track.back() : nullptr));
    }
    return h;
  }

  TrackSample sample(const json& v, const std::string& path, const TrackSample* previous) const {
    r_.expect_object(v, path, {"t", "pos", "quat", "grip", "pedal"});
    TrackSample out;
    const std::string time_path = path_key(path, "t");
    out.t = r_.number(r_.require(v, path, "t", "a time in s >= 0"), time_path);
    if (out.t < 0) r_.fail(time_path, "expected a time >= 0 s, got " + format_number(out.t));
    if (out.t > kMaxDurationS) {
      r_.fail(time_path, "expected a time <= " + format_number(kMaxDurationS) +
                             " s (the longest scenario), got " + format_number(out.t));
    }
    if (previous != nullptr && !(out.t > previous->t)) {
      r_.fail(time_path, "track not sorted in time: expected t > " + format_number(previous->t) +
                             ", got " + format_number(out.t));
    }

    out.pos = io::read_workspace_point(r_, r_.require(v, path, "pos", "[x, y, z] in mm"),
                                       path_key(path, "pos"));

    if (const json* q = JsonReader::find(v, "quat")) {
      const std::string qpath = path_key(path, "quat");
      std::array<double, 4> c{};
      r_.fixed_numbers(*q, qpath, c, "[w, x, y, z]");
      out.quat = Quat(c[0], c[1], c[2], c[3]);
      const double length = out.quat.norm();
      if (!std::isfinite(length)) r_.fail(qpath, "quaternion length is not finite");
      if (length < kMinQuatLength) {
        r_.fail(qpath, length == 0
                           ? std::string("quaternion of zero length")
                           : "quaternion of zero length (got " + format_number(length) + ")");
      }
      if (std::abs(length - 1.0) > kUnitTolerance) out.quat.coeffs() /= length;
    }
    if (const json* g = JsonReader::find(v, "grip")) {
      out.grip = r_.number_in(*g, path_key(path, "grip"), 0.0, kMaxGrip);
    }
    if (const json* p3 = JsonReader::find(v, "pedal")) {
      out.pedal = r_.number_in(*p3, path_key(path, "pedal"), 0.0, kMaxPedal);
    }
    return out;
  }

  JsonReader r_;
  fs::path base_dir_;
};

}  // namespace

DifficultySettings DifficultySettings::overlaid(const DifficultySettings& over) const {
  DifficultySettings out = *this;
  if (over.patient_age_years) out.patient_age_years = over.patient_age_years;
  if (over.anterior_bowing_kpa) out.anterior_bowing_kpa = over.anterior_bowing_kpa;
  if (over.anterior_chamber_depth_mm)
    out.anterior_chamber_depth_mm = over.anterior_chamber_depth_mm;
  if (over.nucleus_hardness) out.nucleus_hardness = over.nucleus_hardness;
  return out;
}

DifficultySettings read_difficulty_settings(const io::JsonReader& r, const json& v,
                                            const std::string& path,
                                            std::initializer_list<std::string_view> extra) {
  struct Field {
    std::string_view name;
    double lo, hi;
    std::optional<double> DifficultySettings::*member;
  };
  // Ranges: published adult values and the anomalies' extremes (docs/drills.md).
  static constexpr Field kFields[] = {
      {"patient_age_years", 1, 100, &DifficultySettings::patient_age_years},
      {"anterior_bowing_kpa", 0, 2, &DifficultySettings::anterior_bowing_kpa},
      {"anterior_chamber_depth_mm", 1.5, 4.5, &DifficultySettings::anterior_chamber_depth_mm},
      {"nucleus_hardness", 0.05, 1, &DifficultySettings::nucleus_hardness}};
  if (!v.is_object()) {
    r.fail(path,
           "expected an object of difficulty settings (patient_age_years, "
           "anterior_bowing_kpa, anterior_chamber_depth_mm, nucleus_hardness), got " +
               io::describe_value(v));
  }
  for (const auto& [key, unused] : v.items()) {
    bool known = std::find(extra.begin(), extra.end(), key) != extra.end();
    for (const Field& f : kFields) known = known || f.name == key;
    if (!known) {
      std::string names;
      for (const Field& f : kFields)
        names += std::string(names.empty() ? "" : ", ") + std::string(f.name);
      for (std::string_view e : extra) names += ", " + std::string(e);
      r.fail(path_key(path, key), "unknown difficulty setting; expected one of: " + names);
    }
  }
  DifficultySettings out;
  for (const Field& f : kFields) {
    if (const json* x = JsonReader::find(v, f.name)) {
      out.*f.member = r.number_in(*x, path_key(path, f.name), f.lo, f.hi);
    }
  }
  return out;
}

std::string_view to_string(Drill drill) {
  return kDrillNames[static_cast<std::size_t>(drill)];
}
std::string_view to_string(ToolKind tool) {
  return kToolNames[static_cast<std::size_t>(tool)];
}
std::string_view to_string(Hand hand) {
  return kHandNames[static_cast<std::size_t>(hand)];
}

std::optional<Drill> parse_drill(std::string_view name) {
  const auto i = index_of(kDrillNames, name);
  return i ? std::optional<Drill>(static_cast<Drill>(*i)) : std::nullopt;
}
std::optional<ToolKind> parse_tool(std::string_view name) {
  const auto i = index_of(kToolNames, name);
  return i ? std::optional<ToolKind>(static_cast<ToolKind>(*i)) : std::nullopt;
}
std::optional<Hand> parse_hand(std::string_view name) {
  const auto i = index_of(kHandNames, name);
  return i ? std::optional<Hand>(static_cast<Hand>(*i)) : std::nullopt;
}

bool operator==(const TrackSample& a, const TrackSample& b) {
  return a.t == b.t && a.pos == b.pos && a.quat.coeffs() == b.quat.coeffs() && a.grip == b.grip &&
         a.pedal == b.pedal;
}

bool operator==(const Scenario& a, const Scenario& b) {
  return a.name == b.name && a.description == b.description && a.drill == b.drill &&
         a.eye == b.eye && a.drill_file == b.drill_file && a.difficulty == b.difficulty &&
         a.difficulty_settings == b.difficulty_settings && a.methods == b.methods &&
         a.dt_s == b.dt_s && a.seed == b.seed && a.duration_s == b.duration_s && a.hands == b.hands;
}

uint64_t Scenario::frame_count() const {
  if (!(dt_s > 0) || !(duration_s > 0)) return 0;
  // The 1e-9 keeps 10 s at 1/120 s from counting 1201 frames because of rounding in the division.
  return static_cast<uint64_t>(std::ceil(duration_s / dt_s - 1e-9));
}

const HandTrack* Scenario::find_hand(Hand hand) const {
  for (const HandTrack& h : hands) {
    if (h.hand == hand) return &h;
  }
  return nullptr;
}

Scenario parse_scenario(std::string_view json_text, const std::string& source,
                        const fs::path& base_dir) {
  const json root = io::parse_json_text(json_text, source);
  return ScenarioParser(source, base_dir).parse(root);
}

Scenario load_scenario(const fs::path& file) {
  const std::string source = file.string();
  std::error_code ec;
  const fs::file_status st = fs::status(file, ec);
  if (!fs::exists(st)) throw InputError(source + ": scenario file not found");
  if (fs::is_directory(st)) {
    throw InputError(source + ": is a directory; expected a scenario JSON file");
  }
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(source + ": cannot open scenario file for reading");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw InputError(source + ": read error");
  return parse_scenario(text, source, fs::absolute(file).parent_path());
}

json to_json(const Scenario& s) {
  json j = json::object();
  if (!s.name.empty()) j["name"] = s.name;
  if (!s.description.empty()) j["description"] = s.description;
  j["drill"] = std::string(to_string(s.drill));

  json eye = {{"level", s.eye.level}, {"capsule_layout", s.eye.capsule_layout}};
  if (!s.eye.overrides.empty()) eye["overrides"] = s.eye.overrides;
  if (s.eye.params_file) eye["params"] = s.eye.params_file->generic_string();
  if (!s.eye.meshes.empty()) {
    json meshes = json::object();
    for (const auto& [body, file] : s.eye.meshes) meshes[body] = file.generic_string();
    eye["meshes"] = std::move(meshes);
  }
  if (s.drill_file) j["drill_file"] = s.drill_file->generic_string();
  const DifficultySettings& d = s.difficulty_settings;
  if (d == DifficultySettings{}) {
    if (!s.difficulty.empty()) j["difficulty"] = s.difficulty;
  } else {
    json dj = json::object();
    if (!s.difficulty.empty()) dj["level"] = s.difficulty;
    if (d.patient_age_years) dj["patient_age_years"] = *d.patient_age_years;
    if (d.anterior_bowing_kpa) dj["anterior_bowing_kpa"] = *d.anterior_bowing_kpa;
    if (d.anterior_chamber_depth_mm) dj["anterior_chamber_depth_mm"] = *d.anterior_chamber_depth_mm;
    if (d.nucleus_hardness) dj["nucleus_hardness"] = *d.nucleus_hardness;
    j["difficulty"] = std::move(dj);
  }
  j["eye"] = std::move(eye);
  if (!s.methods.empty()) j["methods"] = s.methods;
  j["dt_s"] = s.dt_s;
  j["seed"] = s.seed;
  j["duration_s"] = s.duration_s;

  json hands = json::object();
  for (const HandTrack& h : s.hands) {
    json track = json::array();
    for (const TrackSample& x : h.track) {
      json sample = {{"t", x.t},
                     {"pos", {x.pos.x(), x.pos.y(), x.pos.z()}},
                     {"quat", {x.quat.w(), x.quat.x(), x.quat.y(), x.quat.z()}}};
      if (x.grip != 0) sample["grip"] = x.grip;
      if (x.pedal != 0) sample["pedal"] = x.pedal;
      track.push_back(std::move(sample));
    }
    hands[std::string(to_string(h.hand))] = {{"tool", std::string(to_string(h.tool))},
                                             {"track", std::move(track)}};
  }
  j["hands"] = std::move(hands);
  return j;
}

}  // namespace phaco
