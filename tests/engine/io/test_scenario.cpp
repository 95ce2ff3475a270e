#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "engine/core/error.hpp"
#include "engine/io/bounds.hpp"
#include "engine/io/scenario.hpp"
#include "engine/io/track.hpp"
#include "tests/support/expect_invalid.hpp"

namespace phaco {
namespace {

namespace fs = std::filesystem;

const fs::path kSourceDir = PHACO_SOURCE_DIR;
const fs::path kScenarioDir = kSourceDir / "data/scenarios";
const fs::path kBadDir = kSourceDir / "tests/engine/io/bad_scenarios";

using phaco::test::input_error_of;

Quat quat_about(const Vec3& axis, double angle) {
  return Quat(Eigen::AngleAxisd(angle, axis.normalized()));
}

TrackSample make_sample(double t, Vec3 pos, Quat q = Quat::Identity(), double grip = 0,
                        double pedal = 0) {
  TrackSample s;
  s.t = t;
  s.pos = pos;
  s.quat = q;
  s.grip = grip;
  s.pedal = pedal;
  return s;
}

// ------------------------------------------------------------------ good files

TEST(Scenario, ExampleFilesParseAndAreConsistent) {
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(kScenarioDir)) {
    if (entry.path().extension() == ".json") files.push_back(entry.path());
  }
  ASSERT_GE(files.size(), 4u);
  for (const fs::path& file : files) {
    SCOPED_TRACE(file.string());
    const Scenario s = load_scenario(file);
    EXPECT_EQ(s.source, file.string());
    EXPECT_FALSE(s.name.empty());
    ASSERT_FALSE(s.hands.empty());
    for (const HandTrack& h : s.hands) {
      for (const TrackSample& x : h.track) {
        EXPECT_NEAR(x.quat.norm(), 1.0, 1e-12);
        // Every scripted sample lies inside the scenario's time span.
        EXPECT_LE(x.t, s.duration_s);
      }
    }
  }
}

TEST(Scenario, CapsulorhexisDemoContent) {
  const Scenario s = load_scenario(kScenarioDir / "capsulorhexis_demo.json");
  EXPECT_EQ(s.drill, Drill::Capsulorhexis);
  EXPECT_EQ(s.seed, 7u);
  EXPECT_DOUBLE_EQ(s.dt_s, 1.0 / 120.0);
  EXPECT_EQ(s.frame_count(), static_cast<uint64_t>(std::llround(s.duration_s * 120)));
  ASSERT_EQ(s.hands.size(), 2u);
  EXPECT_EQ(s.hands[0].hand, Hand::Left);  // left first
  EXPECT_EQ(s.hands[0].tool, ToolKind::Forceps);
  EXPECT_EQ(s.hands[1].hand, Hand::Right);
  EXPECT_EQ(s.hands[1].tool, ToolKind::Cystotome);
  ASSERT_NE(s.find_hand(Hand::Right), nullptr);

  // The cystotome goes below the anterior capsule surface near the axis (the puncture).
  double lowest = 1e9;
  for (const TrackSample& x : s.hands[1].track) {
    if (std::hypot(x.pos.x(), x.pos.y()) < 0.5) lowest = std::min(lowest, x.pos.z());
  }
  EXPECT_LT(lowest, 1.8);

  // The forceps pulls round a circle of radius 2.6 mm closed (grip 1) and regrasps 3 times.
  int closed_on_circle = 0;
  int regrasps = 0;
  double previous_grip = 0;
  for (const TrackSample& x : s.hands[0].track) {
    if (x.grip == 1 && std::abs(std::hypot(x.pos.x(), x.pos.y()) - 2.6) < 1e-3) ++closed_on_circle;
    if (previous_grip == 1 && x.grip == 0) ++regrasps;
    previous_grip = x.grip;
  }
  EXPECT_GE(closed_on_circle, 4 * 12);
  EXPECT_EQ(regrasps, 4);  // three regrasps and the final release
}

TEST(Scenario, DefaultsAndOptionalFields) {
  const fs::path dir = fs::temp_directory_path() / "phaco_test_scenario_optional";
  fs::create_directories(dir / "meshes");
  std::ofstream(dir / "meshes/capsule.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  std::ofstream(dir / "eye.json") << "{}\n";
  const std::string text = R"({
    "name": "optional fields", "description": "every optional field set",
    "drill": "phaco_sculpting",
    "eye": { "level": 0, "capsule_layout": "isotropic", "params": "eye.json",
             "overrides": { "capsule.youngs_modulus_kpa": 3000, "lens.nucleus_fraction": 0.7 },
             "meshes": { "capsule": "meshes/capsule.obj" } },
    "dt_s": 0.001, "seed": 18446744073709551615, "duration_s": 0.0105,
    "hands": { "right": { "tool": "phaco_probe", "track": [
      { "t": 0, "pos": [1, 2, 3], "quat": [2, 0, 0, 0], "pedal": 3 } ] } }
  })";
  const Scenario s = parse_scenario(text, "inline.json", dir);
  EXPECT_EQ(s.name, "optional fields");
  EXPECT_EQ(s.eye.level, 0);
  EXPECT_EQ(s.eye.capsule_layout, "isotropic");
  EXPECT_EQ(s.eye.overrides.at("capsule.youngs_modulus_kpa"), 3000.0);
  ASSERT_TRUE(s.eye.params_file.has_value());
  EXPECT_TRUE(fs::equivalent(*s.eye.params_file, dir / "eye.json"));
  EXPECT_TRUE(s.eye.params_file->is_absolute());
  EXPECT_TRUE(fs::equivalent(s.eye.meshes.at("capsule"), dir / "meshes/capsule.obj"));
  EXPECT_EQ(s.seed, 18446744073709551615u);
  EXPECT_EQ(s.frame_count(), 11u);  // 10.5 steps round up
  ASSERT_EQ(s.hands.size(), 1u);
  const TrackSample& x = s.hands[0].track[0];
  EXPECT_EQ(x.quat.coeffs(), Quat::Identity().coeffs());  // normalised from (2, 0, 0, 0)
  EXPECT_EQ(x.pedal, 3.0);
  EXPECT_EQ(x.grip, 0.0);

  // Round trip through text with paths written resolved.
  const Scenario back = parse_scenario(to_json(s).dump(2), "back.json", fs::path("/nonexistent"));
  EXPECT_TRUE(back == s);

  // Minimal file: the documented defaults.
  const Scenario m = parse_scenario(
      R"({"drill": "capsulorhexis", "duration_s": 10,
          "hands": {"left": {"tool": "hook", "track": [{"t": 0, "pos": [0, 0, 3]}]}}})",
      "min.json", dir);
  EXPECT_EQ(m.eye.level, 3);
  EXPECT_EQ(m.eye.capsule_layout, "curvilinear");
  EXPECT_DOUBLE_EQ(m.dt_s, 1.0 / 120.0);
  EXPECT_EQ(m.seed, 0u);
  EXPECT_EQ(m.frame_count(), 1200u);
  EXPECT_FALSE(m.eye.params_file.has_value());
  EXPECT_TRUE(m.methods.empty());

  // Method choices are kept verbatim (names are the scene's to check) and survive a round trip.
  const Scenario with_methods = parse_scenario(
      R"({"drill": "capsulorhexis", "duration_s": 1,
          "methods": {"capsule.integrator": "xpbd", "capsule.spring_law": "quadratic"},
          "hands": {"left": {"tool": "forceps", "track": [{"t": 0, "pos": [0, 0, 3]}]}}})",
      "methods.json", dir);
  EXPECT_EQ(with_methods.methods.at("capsule.integrator"), "xpbd");
  EXPECT_EQ(with_methods.methods.size(), 2u);
  const Scenario methods_back = parse_scenario(to_json(with_methods).dump(), "back.json", dir);
  EXPECT_TRUE(methods_back == with_methods);
  fs::remove_all(dir);
}

TEST(Scenario, RoundTripOfExampleFiles) {
  for (const auto& entry : fs::directory_iterator(kScenarioDir)) {
    SCOPED_TRACE(entry.path().string());
    const Scenario s = load_scenario(entry.path());
    const Scenario back = parse_scenario(to_json(s).dump(), s.source, kScenarioDir);
    EXPECT_TRUE(back == s);
    // A second trip is the identity on the JSON as well.
    EXPECT_EQ(to_json(back), to_json(s));
  }
}

TEST(Scenario, NamesRoundTrip) {
  for (Drill d : {Drill::CornealIncision, Drill::Capsulorhexis, Drill::PhacoSculpting,
                  Drill::NucleusRemoval}) {
    EXPECT_EQ(parse_drill(to_string(d)), d);
  }
  for (ToolKind k :
       {ToolKind::Forceps, ToolKind::Keratome, ToolKind::Cystotome, ToolKind::PhacoProbe,
        ToolKind::Hook, ToolKind::Aspirator, ToolKind::Chopper}) {
    EXPECT_EQ(parse_tool(to_string(k)), k);
  }
  EXPECT_EQ(to_string(ToolKind::PhacoProbe), "phaco_probe");
  EXPECT_EQ(to_string(ToolKind::Chopper), "chopper");
  EXPECT_EQ(to_string(Drill::NucleusRemoval), "nucleus_removal");
  EXPECT_EQ(parse_hand("left"), Hand::Left);
  EXPECT_FALSE(parse_drill("capsulotomy").has_value());
  EXPECT_FALSE(parse_tool("Forceps").has_value());
}

// ------------------------------------------------------------------ bad files

struct BadCase {
  const char* file;
  std::vector<std::string> expected;  // substrings of the message, in order
};

const std::vector<BadCase> kBadCases = {
    {"unknown_drill.json",
     {"unknown_drill.json: drill: unknown drill 'capsulotomy'; expected one of: corneal_incision, "
      "capsulorhexis, phaco_sculpting"}},
    {"drill_null.json", {"drill_null.json: drill: expected a drill name (one of: ", "got null"}},
    {"missing_drill.json",
     {"missing_drill.json: drill: missing required field; expected one of: corneal_incision"}},
    {"unknown_tool.json",
     {"unknown_tool.json: hands.right.tool: unknown tool 'scalpel'; expected one of: forceps, "
      "keratome, cystotome, phaco_probe, hook, aspirator"}},
    {"unknown_hand.json",
     {"unknown_hand.json: hands.middle: unknown hand 'middle'; expected one of: left, right"}},
    {"unknown_field_root.json",
     {"unknown_field_root.json: seeds: unknown field 'seeds'; expected one of: name, description, "
      "drill, drill_file, difficulty, eye, methods, dt_s, seed, duration_s, hands"}},
    {"unknown_field_eye.json",
     {"unknown_field_eye.json: eye.levle: unknown field 'levle'; expected one of: level, "
      "capsule_layout, overrides, params, meshes"}},
    {"unknown_field_hand.json",
     {"unknown_field_hand.json: hands.right.tools: unknown field 'tools'; expected one of: tool, "
      "track"}},
    {"unknown_field_sample.json",
     {"unknown_field_sample.json: hands.right.track[1].grp: unknown field 'grp'; expected one of: "
      "t, pos, quat, grip, pedal"}},
    {"unknown_mesh_body.json",
     {"unknown_mesh_body.json: eye.meshes.cornia: unknown field 'cornia'; expected one of: cornea, "
      "capsule, iris, globe, lens_surface"}},
    {"track_not_sorted.json",
     {"track_not_sorted.json: hands.right.track[2].t: track not sorted in time: expected t > 2, "
      "got 1.5"}},
    {"duplicate_t.json",
     {"duplicate_t.json: hands.right.track[2].t: track not sorted in time: expected t > 1, got 1"}},
    {"negative_t.json",
     {"negative_t.json: hands.right.track[0].t: expected a time >= 0 s, got -0.5"}},
    {"empty_track.json",
     {"empty_track.json: hands.right.track: expected at least one track sample, got an empty "
      "array"}},
    {"sample_not_object.json",
     {"sample_not_object.json: hands.right.track[0]: expected an object, got an array of 3 "
      "elements"}},
    {"missing_pos.json",
     {"missing_pos.json: hands.right.track[1].pos: missing required field; expected [x, y, z]"}},
    {"nan_syntax.json",
     {"nan_syntax.json: line 26, column 13: syntax error",
      "JSON has no NaN or Infinity; every number must be finite"}},
    {"trailing_comma.json", {"trailing_comma.json: line 4, column 1: syntax error"}},
    {"inf_in_pos.json",
     {"inf_in_pos.json: hands.right.track[1].pos[2]: expected a finite number, got 1e999"}},
    {"zero_quat.json", {"zero_quat.json: hands.right.track[0].quat: quaternion of zero length"}},
    {"quat_wrong_length.json",
     {"quat_wrong_length.json: hands.right.track[1].quat: expected an array of 4 numbers "
      "[w, x, y, z], got an array of 3 elements"}},
    {"pos_wrong_length.json",
     {"pos_wrong_length.json: hands.right.track[0].pos: expected an array of 3 numbers [x, y, z], "
      "got an array of 2 elements"}},
    {"string_for_number.json",
     {"string_for_number.json: hands.right.track[1].t: expected a number, got string \"1.0\""}},
    {"bool_for_number.json",
     {"bool_for_number.json: hands.right.track[1].grip: expected a number, got boolean true"}},
    {"name_not_string.json", {"name_not_string.json: name: expected a string, got 42"}},
    {"negative_level.json",
     {"negative_level.json: eye.level: expected an integer in 0..8, got -1"}},
    {"level_9.json", {"level_9.json: eye.level: expected an integer in 0..8, got 9"}},
    {"level_not_integer.json",
     {"level_not_integer.json: eye.level: expected an integer in 0..8, got 2.5"}},
    {"unknown_capsule_layout.json",
     {"unknown_capsule_layout.json: eye.capsule_layout: unknown capsule layout 'radial'; expected "
      "one of: curvilinear, isotropic"}},
    {"missing_mesh_file.json",
     {"missing_mesh_file.json: eye.meshes.capsule: mesh file not found: ",
      "bad_scenarios/no_such_capsule.obj"}},
    {"mesh_is_directory.json",
     {"mesh_is_directory.json: eye.meshes.capsule: mesh file is a directory, expected a regular "
      "file: ",
      "bad_scenarios"}},
    {"missing_params_file.json",
     {"missing_params_file.json: eye.params: eye parameter file not found: ",
      "bad_scenarios/no_such_eye_params.json"}},
    {"bad_override_value.json",
     {"bad_override_value.json: eye.overrides[\"capsule.youngs_modulus_kpa\"]: expected a number, "
      "got string \"stiff\""}},
    {"override_key_without_dot.json",
     {"override_key_without_dot.json: eye.overrides.youngs_modulus_kpa: override key must have "
      "the form 'section.key'",
      "got 'youngs_modulus_kpa'"}},
    {"negative_dt.json",
     {"negative_dt.json: dt_s: expected a time step in 1e-05..0.1 s, got -0.01"}},
    {"pos_beyond_workspace.json",
     {"pos_beyond_workspace.json: hands.right.track[1].pos[0]: expected a coordinate in -50..50 mm "
      "(the workspace around the eye's origin), got 1.2e+19"}},
    {"t_beyond_longest_scenario.json",
     {"t_beyond_longest_scenario.json: hands.right.track[1].t: expected a time <= 3600 s (the "
      "longest scenario), got 1e+300"}},
    {"dt_longer_than_duration.json",
     {"dt_longer_than_duration.json: dt_s: time step 0.1 s is longer than duration_s 0.05 s"}},
    {"missing_duration.json",
     {"missing_duration.json: duration_s: missing required field; expected a duration > 0 and "
      "<= 3600 s"}},
    {"duration_too_long.json",
     {"duration_too_long.json: duration_s: expected a duration > 0 and <= 3600 s, got 7200"}},
    {"negative_seed.json",
     {"negative_seed.json: seed: expected a non-negative integer (0..18446744073709551615), got "
      "-3"}},
    {"seed_too_large.json", {"seed_too_large.json: seed: expected a non-negative integer"}},
    {"grip_1_5.json",
     {"grip_1_5.json: hands.left.track[0].grip: expected a number in 0..1, got 1.5"}},
    {"pedal_4.json",
     {"pedal_4.json: hands.right.track[1].pedal: expected a number in 0..3, got 4"}},
    {"no_hands.json",
     {"no_hands.json: hands: expected at least one hand (\"left\" or \"right\"), got an empty "
      "object"}},
    {"hands_array.json",
     {"hands_array.json: hands: expected an object with a \"left\" and/or \"right\" hand, got an "
      "array of 1 element"}},
    {"empty.json", {"empty.json: $: file is empty; expected a JSON object"}},
    {"methods_not_object.json",
     {"methods_not_object.json: methods: expected an object of \"body.setting\": \"choice\""}},
    {"methods_key_without_body.json",
     {"methods_key_without_body.json: methods.integrator: method key must have the form "
      "'body.setting'"}},
    {"methods_value_not_string.json",
     {"methods_value_not_string.json: methods[\"capsule.integrator\"]: expected a string"}},
    {"top_level_array.json",
     {"top_level_array.json: $: expected a JSON object at the top level, got an array of 1 "
      "element"}},
    {"duplicate_field.json",
     {"duplicate_field.json: drill: duplicate field 'drill' (each field may appear only once)"}},
};

TEST(Scenario, BadFilesFailWithPreciseMessages) {
  // Every file in the folder has a row, and every row a file.
  std::size_t files = 0;
  for (const auto& entry : fs::directory_iterator(kBadDir)) {
    if (entry.path().extension() != ".json") continue;
    ++files;
    const std::string name = entry.path().filename().string();
    bool listed = false;
    for (const BadCase& c : kBadCases) listed = listed || name == c.file;
    EXPECT_TRUE(listed) << name << " has no row in kBadCases";
  }
  EXPECT_EQ(files, kBadCases.size());
  EXPECT_GE(kBadCases.size(), 25u);

  for (const BadCase& c : kBadCases) {
    SCOPED_TRACE(c.file);
    const fs::path file = kBadDir / c.file;
    const std::string message = input_error_of([&] { load_scenario(file); });
    // FILE as given comes first.
    EXPECT_EQ(message.rfind(file.string() + ": ", 0), 0u) << message;
    std::size_t from = 0;
    for (const std::string& part : c.expected) {
      const std::size_t at = message.find(part, from);
      EXPECT_NE(at, std::string::npos) << "missing \"" << part << "\" in: " << message;
      if (at != std::string::npos) from = at + part.size();
    }
  }
}

TEST(Scenario, MissingFileAndDirectory) {
  const fs::path missing = kBadDir / "does_not_exist.json";
  EXPECT_EQ(input_error_of([&] { load_scenario(missing); }),
            missing.string() + ": scenario file not found");
  EXPECT_EQ(input_error_of([&] { load_scenario(kBadDir); }),
            kBadDir.string() + ": is a directory; expected a scenario JSON file");
}

TEST(Scenario, SyntaxErrorPositionIsLineAndColumn) {
  const std::string text = "{\n  \"drill\": \"capsulorhexis\",\n  \"duration_s\": 5x\n}";
  const std::string message = input_error_of([&] { parse_scenario(text, "s.json", "."); });
  EXPECT_EQ(message.rfind("s.json: line 3, column 18: ", 0), 0u) << message;
  EXPECT_EQ(message.find("json.exception"), std::string::npos) << message;
  // Unterminated input points past the last character.
  const std::string cut = input_error_of([&] { parse_scenario("{\n \"drill\": ", "c.json", "."); });
  EXPECT_EQ(cut.rfind("c.json: line 2, column 11: ", 0), 0u) << cut;
}

TEST(Scenario, DuplicateKeyDeepInTrackNamesItsPath) {
  const std::string text = R"({"drill": "capsulorhexis", "duration_s": 5, "hands": {"left":
      {"tool": "forceps", "track": [{"t": 0, "pos": [0, 0, 3]}, {"t": 1, "t": 2, "pos": [0, 0, 3]}]}}})";
  EXPECT_EQ(input_error_of([&] { parse_scenario(text, "d.json", "."); }),
            "d.json: hands.left.track[1].t: duplicate field 't' (each field may appear only once)");
}

// Issue 18 item 1: each bound of a scenario, at its edge (accepted) and just past it (an error
// naming the field): positions in the workspace (±kWorkspaceHalfMm per axis), times and the step.
TEST(Scenario, BoundsAcceptTheirEdgeAndRejectJustPastIt) {
  const nlohmann::json base = nlohmann::json::parse(R"({
    "drill": "capsulorhexis", "dt_s": 0.01, "duration_s": 3600,
    "hands": { "right": { "tool": "cystotome", "track": [
      { "t": 0, "pos": [0, 0, 3.5] }, { "t": 2, "pos": [0, 0, 1.75], "grip": 0, "pedal": 0 } ] } }
  })");
  struct Bound {
    const char* path;  // as the error names it
    const char* pointer;
    double edge, past;
  };
  const double w = kWorkspaceHalfMm;
  const Bound bounds[] = {
      {"hands.right.track[0].pos[0]", "/hands/right/track/0/pos/0", w, w + 1e-9},
      {"hands.right.track[0].pos[1]", "/hands/right/track/0/pos/1", -w, -w - 1e-9},
      {"hands.right.track[1].pos[2]", "/hands/right/track/1/pos/2", w, 1.2e19},
      {"hands.right.track[1].pos[0]", "/hands/right/track/1/pos/0", -w, -1e300},
      {"hands.right.track[1].t", "/hands/right/track/1/t", kMaxDurationS, kMaxDurationS + 1e-6},
      {"dt_s", "/dt_s", kMinStepS, kMinStepS * 0.999},
      {"dt_s", "/dt_s", kMaxStepS, kMaxStepS * 1.001},
      {"duration_s", "/duration_s", kMaxDurationS, kMaxDurationS + 1e-6},
      {"hands.right.track[1].grip", "/hands/right/track/1/grip", 1, 1 + 1e-9},
      {"hands.right.track[1].pedal", "/hands/right/track/1/pedal", 3, 3 + 1e-9},
  };
  for (const Bound& b : bounds) {
    nlohmann::json inside = base;
    inside[nlohmann::json::json_pointer(b.pointer)] = b.edge;
    EXPECT_NO_THROW(parse_scenario(inside.dump(), "b.json", ".")) << b.path << " = " << b.edge;
    nlohmann::json outside = base;
    outside[nlohmann::json::json_pointer(b.pointer)] = b.past;
    const std::string e = input_error_of([&] { parse_scenario(outside.dump(), "b.json", "."); });
    EXPECT_EQ(e.rfind(std::string("b.json: ") + b.path + ": expected ", 0), 0u)
        << b.path << " = " << b.past << ": " << e;
  }
  // The message says what the workspace is.
  nlohmann::json far = base;
  far["hands"]["right"]["track"][1]["pos"][2] = 1e300;
  EXPECT_EQ(input_error_of([&] { parse_scenario(far.dump(), "b.json", "."); }),
            "b.json: hands.right.track[1].pos[2]: expected a coordinate in -50..50 mm (the "
            "workspace around the eye's origin), got 1e+300");
}

TEST(Scenario, DamagedTextOnlyEverThrowsInputError) {
  std::ifstream in(kScenarioDir / "corneal_incision_demo.json", std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(text.size(), 500u);
  // Any other exception type (nlohmann's own, std::filesystem's) would escape the CLI's handler.
  const auto outcome = [](const std::string& damaged) {
    try {
      parse_scenario(damaged, "damaged.json", kScenarioDir);
      return 0;
    } catch (const InputError&) {
      return 1;
    } catch (...) {
      return 2;
    }
  };
  // Every proper prefix is incomplete JSON.
  for (std::size_t n = 0; n < text.size() - 1; ++n) {
    ASSERT_EQ(outcome(text.substr(0, n)), 1) << "prefix of " << n << " characters";
  }
  // Single-character damage: either still a valid scenario or a clean InputError.
  std::mt19937 rng(12345);
  const std::string alphabet = "{}[]:,\"0123456789.-+eE tfnul\\x";
  int rejected = 0;
  for (int i = 0; i < 2000; ++i) {
    std::string damaged = text;
    damaged[rng() % damaged.size()] = alphabet[rng() % alphabet.size()];
    const int result = outcome(damaged);
    ASSERT_NE(result, 2) << damaged;
    rejected += result;
  }
  EXPECT_GT(rejected, 500);
}

// ------------------------------------------------------------------ sample_track

TEST(SampleTrack, LinearAtMidpointsAndExactAtSamples) {
  const Quat qa = quat_about(Vec3::UnitZ(), 0.0);
  const Quat qb = quat_about(Vec3::UnitZ(), 1.0);
  const std::vector<TrackSample> track = {
      make_sample(0.0, Vec3(0, 0, 3.5), qa, 0.0, 0.0),
      make_sample(2.0, Vec3(2, -4, 1.5), qb, 1.0, 3.0),
      make_sample(3.0, Vec3(3, -4, 1.5), qa, 0.5, 0.0),
  };
  const ToolPose mid = sample_track(track, 1.0);
  EXPECT_NEAR((mid.pos - Vec3(1, -2, 2.5)).norm(), 0.0, 1e-15);
  EXPECT_DOUBLE_EQ(mid.grip, 0.5);
  EXPECT_DOUBLE_EQ(mid.pedal, 1.5);
  EXPECT_NEAR(mid.quat.angularDistance(quat_about(Vec3::UnitZ(), 0.5)), 0.0, 1e-12);

  const ToolPose quarter = sample_track(track, 2.25);
  EXPECT_NEAR((quarter.pos - Vec3(2.25, -4, 1.5)).norm(), 0.0, 1e-15);
  EXPECT_DOUBLE_EQ(quarter.grip, 0.875);
  EXPECT_NEAR(quarter.quat.angularDistance(quat_about(Vec3::UnitZ(), 0.75)), 0.0, 1e-12);

  for (const TrackSample& s : track) {
    const ToolPose p = sample_track(track, s.t);
    EXPECT_EQ(p.pos, s.pos);
    EXPECT_EQ(p.quat.coeffs(), s.quat.coeffs());
    EXPECT_EQ(p.grip, s.grip);
    EXPECT_EQ(p.pedal, s.pedal);
  }
}

TEST(SampleTrack, ClampsOutsideTheTrack) {
  const std::vector<TrackSample> track = {make_sample(1.0, Vec3(1, 2, 3), Quat::Identity(), 0.2),
                                          make_sample(2.0, Vec3(4, 5, 6), Quat::Identity(), 0.8)};
  EXPECT_EQ(sample_track(track, -5.0).pos, Vec3(1, 2, 3));
  EXPECT_EQ(sample_track(track, 0.0).grip, 0.2);
  EXPECT_EQ(sample_track(track, 2.5).pos, Vec3(4, 5, 6));
  EXPECT_EQ(sample_track(track, 1e9).grip, 0.8);
  EXPECT_EQ(sample_track(track, std::nan("")).pos, Vec3(1, 2, 3));
  const std::vector<TrackSample> single = {make_sample(0.5, Vec3(7, 8, 9))};
  EXPECT_EQ(sample_track(single, 0.0).pos, Vec3(7, 8, 9));
  EXPECT_EQ(sample_track(single, 3.0).pos, Vec3(7, 8, 9));
  EXPECT_EQ(sample_track({}, 1.0).pos, Vec3::Zero());
}

TEST(SampleTrack, SlerpIsUnitAndTakesTheShortestArc) {
  const Quat a = quat_about(Vec3(1, 1, 0), 0.3);
  Quat b = quat_about(Vec3(0, 1, 2), 2.0);
  b.coeffs() = -b.coeffs();  // same rotation, opposite hemisphere: must not go the long way
  const std::vector<TrackSample> track = {make_sample(0, Vec3::Zero(), a),
                                          make_sample(1, Vec3::Zero(), b)};
  const double total = a.angularDistance(b);
  ASSERT_LT(total, std::numbers::pi);
  for (int i = 0; i <= 20; ++i) {
    const double u = i / 20.0;
    const Quat q = sample_track(track, u).quat;
    EXPECT_NEAR(q.norm(), 1.0, 1e-14);
    // On the geodesic: the angles to both ends add up to the total and split as u : 1 - u.
    EXPECT_NEAR(a.angularDistance(q), u * total, 1e-9);
    EXPECT_NEAR(q.angularDistance(b), (1 - u) * total, 1e-9);
  }
  // Nearly equal quaternions use the normalised-linear branch and stay unit.
  const Quat c = quat_about(Vec3::UnitX(), 1e-6);
  const Quat mid = slerp_shortest(Quat::Identity(), c, 0.5);
  EXPECT_NEAR(mid.norm(), 1.0, 1e-15);
  EXPECT_NEAR(mid.angularDistance(quat_about(Vec3::UnitX(), 0.5e-6)), 0.0, 1e-12);
}

}  // namespace
}  // namespace phaco
