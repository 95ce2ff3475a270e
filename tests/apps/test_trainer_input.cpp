// phaco-trainer in a trainee's hands (issue 24 item 5): under Xvfb, xdotool drives the real window
// with a synthetic pointer, wheel and keys, as a person would, and the trainer's --ui-state file
// (what the trainee sees: the tools' tips and height readouts, the active hand, the Result table)
// is read after each step. One run of the capsulorhexis drill with both hands on the desktop:
//   the controls overlay shows on the drill's first start and F1 hides it;
//   the pointer jumping onto a panel, off the window and back moves neither tool (clutch);
//   Tab switches the active hand (and back);
//   three wheel clicks lower the active tool's height readout by 0.1 mm each;
//   over the recorded track, neither hand moves more than 0.05 mm beyond what the wheel did;
//   at the drill's end the Result table shows names with units and targets as ranges (no raw
//   JSON), every name whole at 1280×720; the recorded track's path lengths show no jump.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/apps/trainer_driver.hpp"
#include "tests/support/environment.hpp"
#include "tests/support/shell.hpp"

namespace phaco {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// The steps, as a trainee would take them; each `snap NAME` copies the newest UI state.
constexpr const char* kScript = R"(
"$T" --drill capsulorhexis --duration 10 --size 1280x720 --ui-state "$D/state.json" --timeout 300 \
  "$@" > "$D/trainer.log" 2>&1 &
P=$!
started
snap() { sleep 0.5; cp "$D/state.json" "$D/$1.json"; }
xdotool mousemove 640 400; wait_for '"controls_shown": true'; snap intro
xdotool key F1; wait_for '"controls_shown": false'; snap s0
xdotool mousemove 100 100; sleep 0.3     # onto the Drill panel
xdotool mousemove 700 420; sleep 0.3     # the view
xdotool mousemove 640 790; sleep 0.3     # below the window
xdotool mousemove 660 380; sleep 0.3     # the view
xdotool mousemove 1000 600; sleep 0.3    # onto the History panel
xdotool mousemove 640 400; snap s2       # the view
xdotool key Tab; wait_for '"active_hand": "left"'; snap s3
xdotool click --repeat 3 --delay 200 4; sleep 1.5; snap s4   # the wheel forward: deeper
xdotool key Tab; wait_for '"active_hand": "right"'; snap s5
for i in $(seq 1200); do grep -qs '"result"' "$D/state.json" && break; sleep 0.1; done
snap end
xdotool key Escape
wait $P
echo "trainer exit $?"
)";

json read_json(const fs::path& f) {
  std::ifstream in(f);
  EXPECT_TRUE(in.good()) << f;
  return in.good() ? json::parse(in) : json::object();
}

const json& tool_of(const json& state, const std::string& hand) {
  for (const json& t : state["tools"])
    if (t["hand"] == hand) return t;
  ADD_FAILURE() << "no " << hand << " tool in " << state.dump();
  static const json none = json::object();
  return none;
}

double distance(const json& a, const json& b) {
  double s = 0;
  for (int i = 0; i < 3; ++i) {
    const double d = a["tip_mm"][i].get<double>() - b["tip_mm"][i].get<double>();
    s += d * d;
  }
  return std::sqrt(s);
}

TEST(TrainerInput, ClutchDepthReadoutTabAndResultAsATraineeUsesThem) {
  PHACO_REQUIRE_TRAINER_DRIVER();
  const fs::path dir =
      fs::temp_directory_path() / ("phaco-trainer-input-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const test::ShellResult r = test::drive_trainer(PHACO_TRAINER_BIN, dir, kScript);
  ASSERT_EQ(r.code, 0) << r.output;
  ASSERT_NE(r.output.find("trainer exit 0"), std::string::npos) << r.output;

  const json intro = read_json(dir / "intro.json"), s0 = read_json(dir / "s0.json"),
             s2 = read_json(dir / "s2.json"), s3 = read_json(dir / "s3.json"),
             s4 = read_json(dir / "s4.json"), s5 = read_json(dir / "s5.json"),
             end = read_json(dir / "end.json");
  EXPECT_TRUE(intro["controls_shown"].get<bool>()) << "the drill's first start names its controls";
  EXPECT_FALSE(s0["controls_shown"].get<bool>()) << "F1 hides them";

  // The right hand is active first and makes the jumps; Tab makes the left hand active for the
  // wheel, and a second Tab the right again.
  const std::string jumper = s0["active_hand"];
  EXPECT_EQ(jumper, "right");
  const std::string wheeled = "left";
  EXPECT_EQ(s3["active_hand"], wheeled) << "Tab switches the active hand";
  EXPECT_EQ(s5["active_hand"], jumper) << "Tab switches it back";

  // The pointer's jumps onto panels, off the window and back moved neither tool.
  for (const char* hand : {"left", "right"})
    EXPECT_LE(distance(tool_of(s0, hand), tool_of(s2, hand)), 0.05) << hand;

  // Three clicks of the wheel: the active tool 0.3 mm lower, its readout too; the other still.
  const json& before = tool_of(s3, wheeled);
  const json& after = tool_of(s4, wheeled);
  ASSERT_TRUE(before["height_mm"].is_number() && after["height_mm"].is_number()) << s4.dump();
  EXPECT_NEAR(after["height_mm"].get<double>() - before["height_mm"].get<double>(), -0.3, 0.02);
  EXPECT_NE(after["readout"], before["readout"]);
  EXPECT_LE(distance(tool_of(s3, jumper), tool_of(s4, jumper)), 0.05);

  // The Result table: formatted, whole, on screen.
  ASSERT_TRUE(end.contains("result")) << end.dump();
  const json& result = end["result"];
  EXPECT_TRUE(result["on_screen"].get<bool>());
  ASSERT_FALSE(result["rows"].empty());
  bool a_range = false;
  for (const json& row : result["rows"]) {
    const std::string target = row["target"];
    EXPECT_EQ(target.find_first_of("{}\":"), std::string::npos) << "raw JSON: " << target;
    EXPECT_TRUE(row["name_fits"].get<bool>()) << row["metric"];
    EXPECT_EQ(std::string(row["metric"]).find('_'), std::string::npos) << row["metric"];
    a_range = a_range || target.find(" – ") != std::string::npos;
  }
  EXPECT_TRUE(a_range) << "the rhexis diameter's target reads as a range";
  // The recorded track over every frame, from the drill's first: the hand the pointer drove while
  // it jumped moved at most 0.05 mm in all (also before any input: the right cystotome once
  // followed its script for a frame or two, 0.07 mm, before its device's first pose); the other,
  // untouched but for the wheel, moved the wheel's 0.3 mm and no more than 0.05 mm besides.
  const json& m = result["metrics"];
  EXPECT_LE(m[jumper + ".path_length_mm"].get<double>(), 0.05);
  EXPECT_NEAR(m[wheeled + ".path_length_mm"].get<double>(), 0.3, 0.05);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace phaco
