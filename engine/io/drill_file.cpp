#include "engine/io/drill_file.hpp"

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
using io::JsonReader;
using io::path_index;
using io::path_key;

constexpr std::array<std::string_view, 6> kBodies{"cornea", "capsule",      "iris",
                                                  "globe",  "lens_surface", "lens"};
// The corneal ports' modes (procedures/scene/tool_ports.hpp).
constexpr std::array<std::string_view, 3> kPortsModes{"off", "measure", "constrain"};
constexpr double kTotalPoints = 100.0;
constexpr double kPointsTolerance = 1e-6;

class DrillParser {
 public:
  explicit DrillParser(const std::string& source) : r_(source) {}

  DrillFile parse(const json& root) {
    if (!root.is_object()) {
      r_.fail("$", "expected a JSON object at the top level, got " + io::describe_value(root));
    }
    r_.expect_object(root, "$",
                     {"drill", "title", "description", "scene", "tools", "targets", "scoring",
                      "guidance", "difficulty", "ports", "attempted_if_any", "complications"});
    DrillFile d;
    d.source = r_.source();
    const json& drill = r_.require(root, "$", "drill", "a drill name");
    const auto parsed = parse_drill(r_.string(drill, "drill"));
    if (!parsed) {
      r_.fail("drill", "unknown drill '" + drill.get<std::string>() +
                           "'; expected one of: corneal_incision, capsulorhexis, phaco_sculpting, "
                           "nucleus_removal");
    }
    d.drill = *parsed;
    d.title = r_.string(r_.require(root, "$", "title", "a title"), "title");
    if (const json* v = JsonReader::find(root, "description")) {
      d.description = r_.string(*v, "description");
    }
    scene(r_.require(root, "$", "scene", "{\"bodies\": [...]}"), d);
    tools(r_.require(root, "$", "tools", "{\"left\": [...], \"right\": [...]}"), d);
    targets(r_.require(root, "$", "targets", "an object of metric → {\"min\", \"max\"}"), d);
    scoring(r_.require(root, "$", "scoring", "an array of {\"metric\", \"weight\", \"falloff\"}"),
            d);
    if (const json* v = JsonReader::find(root, "attempted_if_any")) attempted(*v, d);
    if (const json* v = JsonReader::find(root, "complications")) complications(*v, d);
    if (const json* v = JsonReader::find(root, "guidance")) d.guidance = guidance(*v);
    difficulty(r_.require(root, "$", "difficulty", "{\"default\", \"levels\"}"), d);
    if (const json* v = JsonReader::find(root, "ports")) {
      d.ports = r_.string(*v, "ports");
      if (std::find(kPortsModes.begin(), kPortsModes.end(), d.ports) == kPortsModes.end()) {
        r_.fail("ports",
                "unknown mode '" + d.ports + "'; expected one of: " + io::join_names(kPortsModes));
      }
      // The ports sit at the guidance's incision site and side port (procedures/scene/tool_ports).
      if (d.ports != "off" && (!d.guidance.incision_site || !d.guidance.side_port)) {
        r_.fail("ports", "mode '" + d.ports +
                             "' needs guidance.incision_site and guidance.side_port, where the "
                             "ports are");
      }
    }
    return d;
  }

 private:
  void scene(const json& v, DrillFile& d) const {
    r_.expect_object(v, "scene", {"bodies"});
    const json& bodies = r_.array(r_.require(v, "scene", "bodies", "an array of body names"),
                                  "scene.bodies", "body names");
    if (bodies.empty()) r_.fail("scene.bodies", "expected at least one body, got an empty array");
    for (std::size_t i = 0; i < bodies.size(); ++i) {
      const std::string path = path_index("scene.bodies", i);
      const std::string name = r_.string(bodies[i], path);
      if (std::find(kBodies.begin(), kBodies.end(), name) == kBodies.end()) {
        r_.fail(path, "unknown body '" + name + "'; expected one of: " + io::join_names(kBodies));
      }
      if (std::find(d.bodies.begin(), d.bodies.end(), name) != d.bodies.end()) {
        r_.fail(path, "body '" + name + "' listed twice");
      }
      d.bodies.push_back(name);
    }
    const auto has = [&](std::string_view b) {
      return std::find(d.bodies.begin(), d.bodies.end(), b) != d.bodies.end();
    };
    if (has("lens") && has("lens_surface")) {
      r_.fail("scene.bodies",
              "a scene has the lens either as a surface (lens_surface) or as "
              "tetrahedra (lens), not both");
    }
    // What each drill's systems need (procedures/scene): a wrong scene is a file error, not a
    // silently empty drill.
    const std::vector<std::string_view> needs =
        d.drill == Drill::CornealIncision ? std::vector<std::string_view>{"cornea"}
        : d.drill == Drill::Capsulorhexis ? std::vector<std::string_view>{"capsule"}
                                          : std::vector<std::string_view>{"capsule", "lens"};
    for (std::string_view b : needs) {
      if (!has(b)) {
        r_.fail("scene.bodies", "the " + std::string(to_string(d.drill)) + " drill needs body '" +
                                    std::string(b) + "'");
      }
    }
  }

  void tools(const json& v, DrillFile& d) const {
    r_.expect_object(v, "tools", {"left", "right"});
    for (const char* hand : {"left", "right"}) {
      std::vector<ToolKind>& out = std::string_view(hand) == "left" ? d.left_tools : d.right_tools;
      const json* list = JsonReader::find(v, hand);
      if (!list) continue;
      const std::string path = path_key("tools", hand);
      const json& a = r_.array(*list, path, "tool names");
      for (std::size_t i = 0; i < a.size(); ++i) {
        const std::string ipath = path_index(path, i);
        const auto tool = parse_tool(r_.string(a[i], ipath));
        if (!tool) {
          r_.fail(ipath, "unknown tool '" + a[i].get<std::string>() +
                             "'; expected one of: forceps, keratome, cystotome, phaco_probe, "
                             "hook, aspirator, chopper");
        }
        out.push_back(*tool);
      }
    }
    if (d.left_tools.empty() && d.right_tools.empty()) {
      r_.fail("tools", "expected at least one tool for one hand");
    }
  }

  void targets(const json& v, DrillFile& d) const {
    if (!v.is_object()) {
      r_.fail("targets",
              "expected an object of metric → {\"min\", \"max\"}, got " + io::describe_value(v));
    }
    for (const auto& [name, band] : v.items()) {
      const std::string path = path_key("targets", name);
      if (name.empty()) r_.fail(path, "expected a metric name, got an empty key");
      r_.expect_object(band, path, {"min", "max"});
      TargetBand t;
      if (const json* x = JsonReader::find(band, "min")) {
        t.min = r_.number_in(*x, path_key(path, "min"), -kMaxMetricMagnitude, kMaxMetricMagnitude);
      }
      if (const json* x = JsonReader::find(band, "max")) {
        t.max = r_.number_in(*x, path_key(path, "max"), -kMaxMetricMagnitude, kMaxMetricMagnitude);
      }
      if (!t.min && !t.max) r_.fail(path, "expected \"min\" and/or \"max\", got neither");
      if (t.min && t.max && *t.min > *t.max) {
        r_.fail(path, "min " + format_number(*t.min) + " is above max " + format_number(*t.max));
      }
      d.targets[name] = t;
    }
  }

  void scoring(const json& v, DrillFile& d) const {
    const json& a = r_.array(v, "scoring", "score terms");
    if (a.empty()) r_.fail("scoring", "expected at least one score term, got an empty array");
    double total = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      const std::string path = path_index("scoring", i);
      r_.expect_object(a[i], path, {"metric", "weight", "falloff"});
      ScoreTerm t;
      const std::string mpath = path_key(path, "metric");
      t.metric = r_.string(r_.require(a[i], path, "metric", "a metric name"), mpath);
      if (!d.targets.count(t.metric)) {
        r_.fail(mpath, "metric '" + t.metric +
                           "' has no target in \"targets\"; a term scores "
                           "a metric against its target");
      }
      for (const ScoreTerm& other : d.scoring) {
        if (other.metric == t.metric) r_.fail(mpath, "metric '" + t.metric + "' scored twice");
      }
      t.weight = r_.number_in(r_.require(a[i], path, "weight", "points > 0"),
                              path_key(path, "weight"), 0, kTotalPoints);
      if (!(t.weight > 0)) r_.fail(path_key(path, "weight"), "expected points > 0, got 0");
      t.falloff = r_.number_in(r_.require(a[i], path, "falloff", "a distance >= 0"),
                               path_key(path, "falloff"), 0, kMaxMetricMagnitude);
      total += t.weight;
      d.scoring.push_back(std::move(t));
    }
    if (std::abs(total - kTotalPoints) > kPointsTolerance) {
      r_.fail("scoring", "weights must sum to 100 points, got " + format_number(total));
    }
  }

  void attempted(const json& v, DrillFile& d) const {
    const json& a = r_.array(v, "attempted_if_any", "metric names");
    if (a.empty()) r_.fail("attempted_if_any", "expected at least one metric name, got none");
    for (std::size_t i = 0; i < a.size(); ++i) {
      const std::string path = path_index("attempted_if_any", i);
      std::string name = r_.string(a[i], path);
      if (name.empty()) r_.fail(path, "expected a metric name, got an empty string");
      d.attempted_if_any.push_back(std::move(name));
    }
  }

  void complications(const json& v, DrillFile& d) const {
    const json& a = r_.array(v, "complications", "{\"metric\", \"name\", \"score_cap\"}");
    for (std::size_t i = 0; i < a.size(); ++i) {
      const std::string path = path_index("complications", i);
      r_.expect_object(a[i], path, {"metric", "name", "above", "score_cap"});
      Complication c;
      c.metric =
          r_.string(r_.require(a[i], path, "metric", "a metric name"), path_key(path, "metric"));
      if (c.metric.empty()) r_.fail(path_key(path, "metric"), "expected a metric name, got \"\"");
      c.name = r_.string(r_.require(a[i], path, "name", "what the trainee is told"),
                         path_key(path, "name"));
      if (c.name.empty()) r_.fail(path_key(path, "name"), "expected a name, got \"\"");
      if (const json* x = JsonReader::find(a[i], "above")) {
        c.above =
            r_.number_in(*x, path_key(path, "above"), -kMaxMetricMagnitude, kMaxMetricMagnitude);
      }
      c.score_cap = r_.number_in(r_.require(a[i], path, "score_cap", "points in [0, 100]"),
                                 path_key(path, "score_cap"), 0, kTotalPoints);
      d.complications.push_back(std::move(c));
    }
  }

  Vec3 point(const json& v, const std::string& path) const {
    return io::read_workspace_point(r_, v, path);
  }

  Guidance::Site site(const json& v, const std::string& path) const {
    r_.expect_object(v, path, {"clock_hour", "limbus_distance_mm"});
    Guidance::Site s;
    s.clock_hour = r_.number_in(r_.require(v, path, "clock_hour", "an hour in (0, 12]"),
                                path_key(path, "clock_hour"), 0, 12);
    if (!(s.clock_hour > 0)) r_.fail(path_key(path, "clock_hour"), "expected (0, 12], got 0");
    s.limbus_distance_mm =
        r_.number_in(r_.require(v, path, "limbus_distance_mm", "a distance in mm"),
                     path_key(path, "limbus_distance_mm"), -2, 3);
    return s;
  }

  Guidance guidance(const json& v) const {
    r_.expect_object(v, "guidance",
                     {"grasp_site_mm", "puncture_site_mm", "rhexis_circle", "trench_cross",
                      "incision_site", "side_port"});
    Guidance g;
    if (const json* x = JsonReader::find(v, "grasp_site_mm")) {
      g.grasp_site_mm = point(*x, "guidance.grasp_site_mm");
    }
    if (const json* x = JsonReader::find(v, "puncture_site_mm")) {
      g.puncture_site_mm = point(*x, "guidance.puncture_site_mm");
    }
    if (const json* x = JsonReader::find(v, "rhexis_circle")) {
      const std::string path = "guidance.rhexis_circle";
      r_.expect_object(*x, path, {"centre_mm", "diameter_mm"});
      Guidance::Circle c;
      c.centre_mm = point(r_.require(*x, path, "centre_mm", "[x, y, z]"), path + ".centre_mm");
      c.diameter_mm = r_.number_in(r_.require(*x, path, "diameter_mm", "a diameter in mm"),
                                   path + ".diameter_mm", 1, 9);
      g.rhexis_circle = c;
    }
    if (const json* x = JsonReader::find(v, "trench_cross")) {
      const std::string path = "guidance.trench_cross";
      r_.expect_object(*x, path, {"centre_mm", "first_angle_deg", "arm_length_mm"});
      Guidance::Cross c;
      c.centre_mm = point(r_.require(*x, path, "centre_mm", "[x, y, z]"), path + ".centre_mm");
      c.first_angle_deg = r_.number_in(r_.require(*x, path, "first_angle_deg", "degrees"),
                                       path + ".first_angle_deg", -360, 360);
      c.arm_length_mm = r_.number_in(r_.require(*x, path, "arm_length_mm", "a length in mm"),
                                     path + ".arm_length_mm", 0.1, 6);
      g.trench_cross = c;
    }
    if (const json* x = JsonReader::find(v, "incision_site")) {
      g.incision_site = site(*x, "guidance.incision_site");
    }
    if (const json* x = JsonReader::find(v, "side_port")) {
      g.side_port = site(*x, "guidance.side_port");
    }
    return g;
  }

  void difficulty(const json& v, DrillFile& d) const {
    r_.expect_object(v, "difficulty", {"default", "levels"});
    const json& levels = r_.require(v, "difficulty", "levels", "an object of level → settings");
    if (!levels.is_object() || levels.empty()) {
      r_.fail("difficulty.levels",
              "expected a non-empty object of level → settings, got " + io::describe_value(levels));
    }
    for (const auto& [name, settings] : levels.items()) {
      d.difficulty[name] =
          read_difficulty_settings(r_, settings, path_key("difficulty.levels", name), {});
    }
    d.default_difficulty =
        r_.string(r_.require(v, "difficulty", "default", "a level name"), "difficulty.default");
    if (!d.difficulty.count(d.default_difficulty)) {
      r_.fail("difficulty.default",
              "level '" + d.default_difficulty + "' is not in difficulty.levels");
    }
  }

  JsonReader r_;
};

}  // namespace

std::span<const std::string_view> drill_body_names() {
  return kBodies;
}

DrillFile parse_drill_file(std::string_view json_text, const std::string& source) {
  return DrillParser(source).parse(io::parse_json_text(json_text, source));
}

DrillFile load_drill_file(const fs::path& file) {
  const std::string source = file.string();
  std::error_code ec;
  const fs::file_status st = fs::status(file, ec);
  if (!fs::exists(st)) throw InputError(source + ": drill file not found");
  if (fs::is_directory(st)) throw InputError(source + ": is a directory; expected a drill file");
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(source + ": cannot open drill file for reading");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw InputError(source + ": read error");
  return parse_drill_file(text, source);
}

DifficultySettings resolve_difficulty(const DrillFile& drill, const std::string& level,
                                      const DifficultySettings& explicit_settings,
                                      const std::string& source) {
  const std::string name = level.empty() ? drill.default_difficulty : level;
  const auto it = drill.difficulty.find(name);
  if (it == drill.difficulty.end()) {
    std::string known;
    for (const auto& [k, unused] : drill.difficulty) known += (known.empty() ? "" : ", ") + k;
    throw InputError(source + ": difficulty: unknown level '" + name + "' for drill file " +
                     drill.source + "; expected one of: " + known);
  }
  return it->second.overlaid(explicit_settings);
}

}  // namespace phaco
