// Drill files (issue 7 item 1, engine/io/drill_file.hpp): the shipped ones load and agree with
// their drills; malformed ones are rejected with the file and the JSON path of the problem; the
// difficulty resolves level, then the scenario's explicit settings; scenarios carry the choice.
#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <string>

#include "engine/core/error.hpp"
#include "engine/io/bounds.hpp"
#include "engine/io/drill_file.hpp"
#include "tests/support/expect_invalid.hpp"

namespace phaco {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const fs::path kDrillDir = fs::path(PHACO_SOURCE_DIR) / "data/drills";

using phaco::test::input_error_of;

json valid_drill() {
  return json::parse(R"({
    "drill": "capsulorhexis", "title": "t",
    "scene": { "bodies": ["cornea", "capsule", "lens_surface"] },
    "tools": { "left": ["forceps"], "right": ["cystotome"] },
    "targets": { "rhexis.diameter_mm": { "min": 5.0, "max": 5.5 }, "lens_contacts": { "max": 0 } },
    "scoring": [ { "metric": "rhexis.diameter_mm", "weight": 60, "falloff": 1 },
                 { "metric": "lens_contacts", "weight": 40, "falloff": 3 } ],
    "guidance": { "puncture_site_mm": [0, 0, 1.8],
                  "rhexis_circle": { "centre_mm": [0, 0, 1.8], "diameter_mm": 5.25 } },
    "difficulty": { "default": "standard",
                    "levels": { "standard": {}, "hard": { "patient_age_years": 85,
                                                          "anterior_bowing_kpa": 0.4 } } }
  })");
}

DrillFile parse(const json& j) {
  return parse_drill_file(j.dump(), "d.json");
}

TEST(DrillFile, TheShippedDrillsLoadAndNameTheirDrills) {
  for (const auto& [name, drill] : {std::pair{"corneal_incision", Drill::CornealIncision},
                                    std::pair{"capsulorhexis", Drill::Capsulorhexis},
                                    std::pair{"phaco_sculpting", Drill::PhacoSculpting},
                                    std::pair{"nucleus_removal", Drill::NucleusRemoval}}) {
    const DrillFile d = load_drill_file(kDrillDir / (std::string(name) + ".json"));
    EXPECT_EQ(d.drill, drill) << name;
    double points = 0;
    for (const ScoreTerm& t : d.scoring) {
      points += t.weight;
      EXPECT_TRUE(d.targets.count(t.metric)) << name << ": " << t.metric;
    }
    EXPECT_NEAR(points, 100.0, 1e-9) << name;
    EXPECT_TRUE(d.difficulty.count("standard")) << name;
    EXPECT_TRUE(d.difficulty.count("hard")) << name;
    EXPECT_EQ(d.difficulty.at("standard"), DifficultySettings{})
        << name << ": the standard level is the eye file's patient as is";
    EXPECT_FALSE(d.attempted_if_any.empty()) << name << ": idle tools must score 0";
    EXPECT_FALSE(d.complications.empty()) << name;
  }
  const DrillFile rhexis = load_drill_file(kDrillDir / "capsulorhexis.json");
  ASSERT_TRUE(rhexis.guidance.rhexis_circle);
  EXPECT_DOUBLE_EQ(rhexis.guidance.rhexis_circle->diameter_mm, 5.25);
  EXPECT_EQ(load_drill_file(kDrillDir / "phaco_sculpting.json").bodies.back(), "lens");
}

TEST(DrillFile, ParsesEveryPart) {
  const DrillFile d = parse(valid_drill());
  EXPECT_EQ(d.source, "d.json");
  EXPECT_EQ(d.bodies, (std::vector<std::string>{"cornea", "capsule", "lens_surface"}));
  EXPECT_EQ(d.left_tools, std::vector<ToolKind>{ToolKind::Forceps});
  EXPECT_EQ(d.targets.at("rhexis.diameter_mm"), (TargetBand{5.0, 5.5}));
  EXPECT_FALSE(d.targets.at("lens_contacts").min);
  ASSERT_EQ(d.scoring.size(), 2u);
  EXPECT_EQ(d.scoring[1], (ScoreTerm{"lens_contacts", 40, 3}));
  EXPECT_EQ(*d.guidance.puncture_site_mm, Vec3(0, 0, 1.8));
  EXPECT_FALSE(d.guidance.grasp_site_mm);
  EXPECT_EQ(d.default_difficulty, "standard");
  EXPECT_DOUBLE_EQ(*d.difficulty.at("hard").patient_age_years, 85);
  EXPECT_TRUE(d.attempted_if_any.empty()) << "optional: no list, always attempted";
  EXPECT_TRUE(d.complications.empty());
  json j = valid_drill();
  j["attempted_if_any"] = {"grasps", "lens_contacts"};
  j["complications"] = {
      {{"metric", "rhexis.radial_tearouts"}, {"name", "tear-out"}, {"score_cap", 40}},
      {{"metric", "lens_contacts"}, {"name", "lens hit"}, {"above", 2}, {"score_cap", 30}}};
  const DrillFile c = parse(j);
  EXPECT_EQ(c.attempted_if_any, (std::vector<std::string>{"grasps", "lens_contacts"}));
  ASSERT_EQ(c.complications.size(), 2u);
  EXPECT_EQ(c.complications[0], (Complication{"rhexis.radial_tearouts", "tear-out", 0, 40}));
  EXPECT_EQ(c.complications[1], (Complication{"lens_contacts", "lens hit", 2, 30}));
}

TEST(DrillFile, MalformedFilesNameTheField) {
  struct Case {
    const char* what;
    std::function<void(json&)> edit;
    const char* message;  // must appear in the error
  };
  const Case cases[] = {
      {"unknown field", [](json& j) { j["scenery"] = 1; },
       "d.json: scenery: unknown field 'scenery'"},
      {"no drill", [](json& j) { j.erase("drill"); }, "d.json: drill: missing required field"},
      {"unknown drill", [](json& j) { j["drill"] = "vitrectomy"; }, "drill: unknown drill"},
      {"unknown body", [](json& j) { j["scene"]["bodies"][1] = "retina"; },
       "scene.bodies[1]: unknown body 'retina'"},
      {"body twice", [](json& j) { j["scene"]["bodies"][1] = "cornea"; },
       "scene.bodies[1]: body 'cornea' listed twice"},
      {"scene without its capsule", [](json& j) { j["scene"]["bodies"] = {"cornea"}; },
       "scene.bodies: the capsulorhexis drill needs body 'capsule'"},
      {"both lens forms", [](json& j) { j["scene"]["bodies"].push_back("lens"); },
       "scene.bodies: a scene has the lens either"},
      {"unknown tool", [](json& j) { j["tools"]["right"][0] = "scalpel"; },
       "tools.right[0]: unknown tool 'scalpel'"},
      {"band upside down", [](json& j) { j["targets"]["rhexis.diameter_mm"]["min"] = 6; },
       "targets[\"rhexis.diameter_mm\"]: min 6 is above max 5.5"},
      {"empty band", [](json& j) { j["targets"]["lens_contacts"] = json::object(); },
       "targets.lens_contacts: expected \"min\" and/or \"max\""},
      {"target not a number", [](json& j) { j["targets"]["lens_contacts"]["max"] = "none"; },
       "targets.lens_contacts.max: expected a number"},
      {"weights not 100", [](json& j) { j["scoring"][0]["weight"] = 50; },
       "scoring: weights must sum to 100 points, got 90"},
      {"scored metric without target", [](json& j) { j["scoring"][0]["metric"] = "time_s"; },
       "scoring[0].metric: metric 'time_s' has no target"},
      {"negative falloff", [](json& j) { j["scoring"][1]["falloff"] = -1; }, "scoring[1].falloff"},
      {"guidance point",
       [](json& j) {
         j["guidance"]["puncture_site_mm"] = {0, 0};
       },
       "guidance.puncture_site_mm"},
      {"circle too large", [](json& j) { j["guidance"]["rhexis_circle"]["diameter_mm"] = 12; },
       "guidance.rhexis_circle.diameter_mm"},
      {"default level missing", [](json& j) { j["difficulty"]["default"] = "expert"; },
       "difficulty.default: level 'expert' is not in difficulty.levels"},
      {"age out of range",
       [](json& j) { j["difficulty"]["levels"]["hard"]["patient_age_years"] = 150; },
       "difficulty.levels.hard.patient_age_years"},
      {"unknown setting", [](json& j) { j["difficulty"]["levels"]["hard"]["myopia_d"] = 3; },
       "difficulty.levels.hard.myopia_d: unknown difficulty setting"},
      {"attempt list empty", [](json& j) { j["attempted_if_any"] = json::array(); },
       "attempted_if_any: expected at least one metric name"},
      {"attempt not a name",
       [](json& j) {
         j["attempted_if_any"] = {"grasps", 3};
       },
       "attempted_if_any[1]"},
      {"complication without cap",
       [](json& j) {
         j["complications"] = {{{"metric", "lens_contacts"}, {"name", "n"}}};
       },
       "complications[0].score_cap: missing required field"},
      {"complication cap above 100",
       [](json& j) {
         j["complications"] = {{{"metric", "lens_contacts"}, {"name", "n"}, {"score_cap", 101}}};
       },
       "complications[0].score_cap"},
      {"complication unnamed",
       [](json& j) {
         j["complications"] = {{{"metric", "lens_contacts"}, {"name", ""}, {"score_cap", 40}}};
       },
       "complications[0].name"},
  };
  for (const Case& c : cases) {
    json j = valid_drill();
    c.edit(j);
    const std::string e = input_error_of([&] { parse(j); });
    EXPECT_NE(e.find(c.message), std::string::npos) << c.what << ": " << e;
  }
  EXPECT_NE(input_error_of([] {
              load_drill_file(kDrillDir / "no_such_drill.json");
            }).find("no_such_drill.json: drill file not found"),
            std::string::npos);
  EXPECT_NE(input_error_of([] { parse_drill_file("{", "d.json"); }).find("d.json: line 1"),
            std::string::npos);
}

// Issue 18 item 1: each bound of a drill file, at its edge (accepted) and just past it (an error
// naming the field). Guidance points lie in the scenario workspace; targets and fall-offs within
// ±1e6 of the metrics' units.
TEST(DrillFile, BoundsAcceptTheirEdgeAndRejectJustPastIt) {
  struct Bound {
    const char* path;  // as the error names it
    std::function<void(json&, double)> set;
    double edge, past;
  };
  const double w = kWorkspaceHalfMm;
  const Bound bounds[] = {
      {"targets[\"rhexis.diameter_mm\"].max",
       [](json& j, double v) { j["targets"]["rhexis.diameter_mm"]["max"] = v; }, 1e6, 1.000001e6},
      {"targets[\"rhexis.diameter_mm\"].min",
       [](json& j, double v) { j["targets"]["rhexis.diameter_mm"]["min"] = v; }, -1e6, -1.000001e6},
      {"targets.lens_contacts.max",
       [](json& j, double v) { j["targets"]["lens_contacts"]["max"] = v; }, -1e6, -1e300},
      {"scoring[1].falloff", [](json& j, double v) { j["scoring"][1]["falloff"] = v; }, 1e6, 2e6},
      {"guidance.puncture_site_mm[2]",
       [](json& j, double v) { j["guidance"]["puncture_site_mm"][2] = v; }, w, w + 1e-9},
      {"guidance.grasp_site_mm[0]",
       [](json& j, double v) {
         j["guidance"]["grasp_site_mm"] = {v, 0, 1.5};
       },
       -w, -w - 1e-9},
      {"guidance.rhexis_circle.centre_mm[1]",
       [](json& j, double v) { j["guidance"]["rhexis_circle"]["centre_mm"][1] = v; }, w, 1.2e19},
      {"guidance.trench_cross.centre_mm[0]",
       [](json& j, double v) {
         j["guidance"]["trench_cross"] = {
             {"centre_mm", {v, 0, 1.26}}, {"first_angle_deg", 0}, {"arm_length_mm", 2.5}};
       },
       -w, -1e300},
  };
  for (const Bound& b : bounds) {
    json inside = valid_drill();
    b.set(inside, b.edge);
    EXPECT_NO_THROW(parse(inside)) << b.path << " = " << b.edge;
    json outside = valid_drill();
    b.set(outside, b.past);
    const std::string e = input_error_of([&] { parse(outside); });
    EXPECT_NE(e.find(std::string("d.json: ") + b.path + ": expected "), std::string::npos)
        << b.path << ": " << e;
  }
}

// "ports": the corneal ports' mode when a scenario does not choose (procedures/scene/tool_ports):
// absent is "off"; the shipped drills measure; anything but off/measure/constrain is refused.
TEST(DrillFile, PortsModeIsOptionalAndChecked) {
  EXPECT_EQ(parse(valid_drill()).ports, "off");
  for (const char* mode : {"off", "measure", "constrain"}) {
    json j = valid_drill();
    j["guidance"]["incision_site"] = {{"clock_hour", 3}, {"limbus_distance_mm", 0.3}};
    j["guidance"]["side_port"] = {{"clock_hour", 11}, {"limbus_distance_mm", 0.3}};
    j["ports"] = mode;
    EXPECT_EQ(parse(j).ports, mode);
  }
  json unplaced = valid_drill();  // no incision site or side port: nowhere to put the ports
  unplaced["ports"] = "measure";
  const std::string e0 = input_error_of([&] { parse(unplaced); });
  EXPECT_NE(e0.find("d.json: ports: mode 'measure' needs guidance.incision_site"),
            std::string::npos)
      << e0;
  for (const char* name :
       {"corneal_incision", "capsulorhexis", "phaco_sculpting", "nucleus_removal"}) {
    EXPECT_EQ(load_drill_file(kDrillDir / (std::string(name) + ".json")).ports, "measure") << name;
  }
  json bad = valid_drill();
  bad["ports"] = "sometimes";
  const std::string e = input_error_of([&] { parse(bad); });
  EXPECT_NE(e.find("d.json: ports: unknown mode 'sometimes'; expected one of: off, measure, "
                   "constrain"),
            std::string::npos)
      << e;
  bad["ports"] = true;
  const std::string e2 = input_error_of([&] { parse(bad); });
  EXPECT_NE(e2.find("d.json: ports: expected a string"), std::string::npos) << e2;
}

TEST(DrillFile, DifficultyIsTheLevelWithTheScenarioSettingsOverIt) {
  const DrillFile d = parse(valid_drill());
  EXPECT_EQ(resolve_difficulty(d, "", {}, "s.json"), DifficultySettings{});
  DifficultySettings over;
  over.anterior_bowing_kpa = 1.0;
  over.nucleus_hardness = 0.7;
  const DifficultySettings hard = resolve_difficulty(d, "hard", over, "s.json");
  EXPECT_DOUBLE_EQ(*hard.patient_age_years, 85) << "from the level";
  EXPECT_DOUBLE_EQ(*hard.anterior_bowing_kpa, 1.0) << "the scenario's setting wins";
  EXPECT_DOUBLE_EQ(*hard.nucleus_hardness, 0.7);
  EXPECT_FALSE(hard.anterior_chamber_depth_mm);
  const std::string e = input_error_of([&] { resolve_difficulty(d, "nightmare", {}, "s.json"); });
  EXPECT_NE(e.find("s.json: difficulty: unknown level 'nightmare'"), std::string::npos) << e;
  EXPECT_NE(e.find("expected one of: hard, standard"), std::string::npos) << e;
}

TEST(DrillFile, ScenariosCarryTheDifficultyAndDrillFileAndWriteThemBack) {
  const std::string base = R"("drill": "capsulorhexis", "duration_s": 1,
      "hands": { "right": { "tool": "cystotome", "track": [ { "t": 0, "pos": [0, 0, 3] } ] } })";
  const Scenario named = parse_scenario("{" + base + R"(, "difficulty": "hard"})", "s.json", ".");
  EXPECT_EQ(named.difficulty, "hard");
  EXPECT_EQ(named.difficulty_settings, DifficultySettings{});

  const Scenario custom =
      parse_scenario("{" + base + R"(, "difficulty": {"level": "hard", "patient_age_years": 30,
                                       "anterior_chamber_depth_mm": 2.0},
                     "drill_file": ")" +
                         (kDrillDir / "capsulorhexis.json").string() + "\"}",
                     "s.json", ".");
  EXPECT_EQ(custom.difficulty, "hard");
  EXPECT_DOUBLE_EQ(*custom.difficulty_settings.patient_age_years, 30);
  EXPECT_DOUBLE_EQ(*custom.difficulty_settings.anterior_chamber_depth_mm, 2.0);
  ASSERT_TRUE(custom.drill_file);
  // Recordings are written with to_json: the choice survives the round trip.
  for (const Scenario& s : {named, custom}) {
    EXPECT_EQ(parse_scenario(to_json(s).dump(), "again.json", "."), s);
  }

  for (const auto& [text, message] :
       {std::pair{R"("difficulty": {"age": 30})", "difficulty.age: unknown difficulty setting"},
        std::pair{R"("difficulty": {"anterior_chamber_depth_mm": 0.5})",
                  "difficulty.anterior_chamber_depth_mm"},
        std::pair{R"("difficulty": "")", "difficulty: expected a level name"},
        std::pair{R"("difficulty": 3)", "difficulty: expected an object of difficulty settings"},
        std::pair{R"("drill_file": "nowhere.json")", "drill_file: drill file not found"}}) {
    const std::string e =
        input_error_of([&] { parse_scenario("{" + base + ", " + text + "}", "s.json", "."); });
    EXPECT_NE(e.find(message), std::string::npos) << e;
  }
}

}  // namespace
}  // namespace phaco
