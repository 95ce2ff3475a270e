// phaco-trainer end to end (issue 8 "what it must show"): under Xvfb with Mesa's software
// renderer the trainer runs each drill with scripted devices through the 1 kHz loop and saves its
// view after some simulated seconds; the PIXELS are checked: the eye fills the centre of the frame,
// each hand's instrument shows where its tip is, the capsulorhexis opening shows (the cut edge
// around the red reflex), the sculpted trench shows (exposed nucleus), the incision drill shows
// the sclera. Plus the command line's help and its refusals of bad input.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "engine/io/scenario.hpp"
#include "engine/io/track.hpp"
#include "engine/render/renderer.hpp"
#include "tests/support/environment.hpp"
#include "tests/support/shell.hpp"

namespace phaco {
namespace {

namespace fs = std::filesystem;
using test::shell;
using test::ShellResult;

constexpr int kWidth = 1280, kHeight = 720;
const fs::path kScenarios = fs::path(PHACO_SOURCE_DIR) / "data/scenarios";

bool have_xvfb() {
  return shell("command -v xvfb-run").code == 0;
}

fs::path out_dir() {
  const fs::path d =
      fs::temp_directory_path() / ("phaco-trainer-test-" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

// Runs the trainer on `drill` with both hands scripted and returns the screenshot taken after
// `after_s` simulated seconds.
cv::Mat screenshot(const std::string& drill, double after_s, const std::string& name) {
  const fs::path png = out_dir() / (name + ".png");
  const char* cache = std::getenv("PHACO_CACHE_DIR");
  const std::string cmd = "xvfb-run -a -s '-screen 0 " + std::to_string(kWidth) + "x" +
                          std::to_string(kHeight) + "x24' " + PHACO_TRAINER_BIN + " --drill " +
                          drill + " --left scripted --right scripted --screenshot " + png.string() +
                          " --after " + std::to_string(after_s) + " --timeout 300" +
                          (cache ? std::string(" --cache-dir ") + cache : std::string());
  const ShellResult r = shell(cmd);
  EXPECT_EQ(r.code, 0) << cmd << "\n" << r.output;
  cv::Mat img = cv::imread(png.string(), cv::IMREAD_COLOR);
  EXPECT_FALSE(img.empty()) << png;
  if (!img.empty()) {
    EXPECT_EQ(img.cols, kWidth);
    EXPECT_EQ(img.rows, kHeight);
  }
  return img;
}

// Pixel classes (BGR), chosen from the renderer's palette (docs/rendering.md).
bool background(const cv::Vec3b& p) {
  return p[0] < 25 && p[1] < 25 && p[2] < 25;
}
bool steel(const cv::Vec3b& p) {  // the instruments: grey, unsaturated, neither black nor white
  const int lo = std::min({p[0], p[1], p[2]}), hi = std::max({p[0], p[1], p[2]});
  const int mean = (p[0] + p[1] + p[2]) / 3;
  return hi - lo < 32 && mean > 70 && mean < 205;
}
bool reflex_red(const cv::Vec3b& p) {
  return p[2] > 150 && p[2] > p[1] + 60 && p[2] > p[0] + 80;
}
bool cut_edge(const cv::Vec3b& p) {  // pale pinkish white
  return std::min({p[0], p[1], p[2]}) > 185 && p[2] > p[0] + 15;
}
bool nucleus_yellow(const cv::Vec3b& p) {  // exposed nucleus: pale yellow-tan, not red
  return p[2] > 150 && p[1] > 120 && p[0] < p[1] && p[2] - p[1] < 60 && p[1] - p[0] > 25;
}
bool sclera(const cv::Vec3b& p) {
  return p[2] > 190 && p[1] > 170 && p[0] > 160;
}

template <class Pred>
int count(const cv::Mat& img, cv::Rect r, Pred pred) {
  r &= cv::Rect(0, 0, img.cols, img.rows);
  int n = 0;
  for (int y = r.y; y < r.y + r.height; ++y)
    for (int x = r.x; x < r.x + r.width; ++x) n += pred(img.at<cv::Vec3b>(y, x));
  return n;
}

// Pixels of `pred` inside the circle (cx, cy, r).
template <class Pred>
int count_in_disc(const cv::Mat& img, double cx, double cy, double r, Pred pred) {
  int n = 0;
  for (int y = static_cast<int>(cy - r); y <= static_cast<int>(cy + r); ++y)
    for (int x = static_cast<int>(cx - r); x <= static_cast<int>(cx + r); ++x) {
      if (x < 0 || y < 0 || x >= img.cols || y >= img.rows) continue;
      if (std::hypot(x - cx, y - cy) <= r) n += pred(img.at<cv::Vec3b>(y, x));
    }
  return n;
}

bool iris_brown(const cv::Vec3b& p) {
  return p[2] > 60 && p[2] > p[1] && p[1] > p[0] && p[2] - p[0] > 40;
}

// The eye is in frame: its iris ring shows around the centre, and the centre is drawn.
void expect_eye_in_frame(const cv::Mat& img) {
  const render::Microscope m;
  const auto c = render::project_to_pixel(m, Vec3(0, 0, 1.8), kWidth, kHeight);
  EXPECT_NEAR(c[0], kWidth / 2.0, kWidth / 8.0);
  EXPECT_NEAR(c[1], kHeight / 2.0, kHeight / 8.0);
  const cv::Rect eye(static_cast<int>(c[0]) - 300, static_cast<int>(c[1]) - 300, 600, 600);
  EXPECT_GT(count(img, eye, iris_brown), 20000) << "the iris ring";
  // Inside the limbus nothing is background.
  const double limbus =
      std::abs(render::project_to_pixel(m, Vec3(5.5, 0, 1.2), kWidth, kHeight)[0] - c[0]);
  const double pupil =
      std::abs(render::project_to_pixel(m, Vec3(3.75, 0, 1.8), kWidth, kHeight)[0] - c[0]);
  const int ring = count_in_disc(img, c[0], c[1], limbus, background) -
                   count_in_disc(img, c[0], c[1], pupil, background);
  EXPECT_LT(ring, M_PI * (limbus * limbus - pupil * pupil) / 20) << "the iris ring is drawn";
}

// Each scripted hand's instrument shows near where its track puts the tip at `t_s`.
void expect_tools_at_their_tips(const cv::Mat& img, const std::string& scenario_file, double t_s) {
  const Scenario s = load_scenario(kScenarios / scenario_file);
  const render::Microscope microscope;  // the trainer's default view
  for (const HandTrack& h : s.hands) {
    const ToolPose pose = sample_track(h.track, t_s);
    const auto px = render::project_to_pixel(microscope, pose.pos, kWidth, kHeight);
    // Open forceps jaws straddle the tip: look in a box about a jaw's spread.
    const cv::Rect around(static_cast<int>(px[0]) - 60, static_cast<int>(px[1]) - 60, 120, 120);
    EXPECT_GT(count(img, around, steel), 40) << to_string(h.hand) << " " << to_string(h.tool)
                                             << " near pixel (" << px[0] << ", " << px[1] << ")";
  }
}

class TrainerCli : public ::testing::Test {
 protected:
  void SetUp() override {
#if defined(__SANITIZE_ADDRESS__)
    GTEST_SKIP() << "whole drills in real time under ASan and llvmpipe; the Release pass runs them";
#endif
    PHACO_REQUIRE_ENVIRONMENT(have_xvfb(),
                              "xvfb-run not found (scripts/install-deps.sh installs xvfb)");
  }
};

TEST_F(TrainerCli, CapsulorhexisShowsTheEyeTheToolsAndTheOpening) {
  const double before_s = 1.0, after_s = 11.0;  // the expert's disc comes free at ~10 s
  const cv::Mat start = screenshot("capsulorhexis", before_s, "rhexis_start");
  const cv::Mat end = screenshot("capsulorhexis", after_s, "rhexis_end");
  ASSERT_FALSE(start.empty());
  ASSERT_FALSE(end.empty());
  expect_eye_in_frame(end);
  expect_tools_at_their_tips(start, "capsulorhexis_expert.json", before_s);
  expect_tools_at_their_tips(end, "capsulorhexis_expert.json", after_s);
  // The red reflex fills the pupil; the opening adds the cut capsule's edges (pale ribbons, pinkish
  // white: the renderer's cut-edge colour over the reflex) that the intact capsule has nowhere.
  // Pixels pale at the end and not at the start, inside a disc just wider than the opening (the
  // microscope's fixed highlight is pale in both and so not counted; the steel instruments are
  // not pale in this sense).
  const render::Microscope m;
  const auto c = render::project_to_pixel(m, Vec3(0, 0, 1.8), kWidth, kHeight);
  const auto rim = render::project_to_pixel(m, Vec3(3.0, 0, 1.8), kWidth, kHeight);
  const double r = std::abs(rim[0] - c[0]);  // 3 mm: just outside the 5.3 mm opening
  EXPECT_GT(count_in_disc(end, c[0], c[1], r, reflex_red), M_PI * r * r / 4) << "the red reflex";
  int new_edges = 0;
  for (int y = static_cast<int>(c[1] - r); y <= static_cast<int>(c[1] + r); ++y)
    for (int x = static_cast<int>(c[0] - r); x <= static_cast<int>(c[0] + r); ++x)
      if (std::hypot(x - c[0], y - c[1]) <= r)
        new_edges += cut_edge(end.at<cv::Vec3b>(y, x)) && !cut_edge(start.at<cv::Vec3b>(y, x));
  RecordProperty("new_edge_pixels", new_edges);
  EXPECT_GT(new_edges, 800) << "the opening's cut edge and flap";
}

TEST_F(TrainerCli, SculptingShowsTheTrench) {
  const double t_s = 14.0;
  const cv::Mat img = screenshot("phaco_sculpting", t_s, "sculpting");
  ASSERT_FALSE(img.empty());
  expect_eye_in_frame(img);
  expect_tools_at_their_tips(img, "phaco_sculpting_expert.json", t_s);
  const int exposed = count(img, cv::Rect(0, 0, kWidth, kHeight), nucleus_yellow);
  RecordProperty("nucleus_pixels", exposed);
  EXPECT_GT(exposed, 300) << "the trench's exposed nucleus";
}

TEST_F(TrainerCli, IncisionShowsTheScleraAndTheKeratome) {
  const double t_s = 1.2;
  const cv::Mat img = screenshot("corneal_incision", t_s, "incision");
  ASSERT_FALSE(img.empty());
  expect_eye_in_frame(img);
  expect_tools_at_their_tips(img, "corneal_incision_expert.json", t_s);
  EXPECT_GT(count(img, cv::Rect(0, 0, kWidth, kHeight), sclera), kWidth * kHeight / 8);
  // The lens is behind the pupil (issue 20 item 5): the red reflex fills its centre, 2 mm about
  // the axis, where the keratome (at 3 o'clock, by the limbus) is not; without it the disc is
  // black.
  const render::Microscope m;
  const auto c = render::project_to_pixel(m, Vec3(0, 0, 1.8), kWidth, kHeight);
  const double r =
      std::abs(render::project_to_pixel(m, Vec3(2.0, 0, 1.8), kWidth, kHeight)[0] - c[0]);
  EXPECT_GT(count_in_disc(img, c[0], c[1], r, reflex_red), M_PI * r * r / 2) << "the red reflex";
}

// With its panels on, a drill that reaches its end is finished by the UI: scored and stored for the
// trainee, so `phaco history` lists it (the trainer's records are phaco's).
TEST_F(TrainerCli, AFinishedDrillIsStoredForTheTrainee) {
  const fs::path db = out_dir() / "records.sqlite";
  fs::remove(db);
  const char* cache = std::getenv("PHACO_CACHE_DIR");
  const std::string cmd =
      "xvfb-run -a -s '-screen 0 1280x720x24' " + std::string(PHACO_TRAINER_BIN) +
      " --drill capsulorhexis --left track --right track --duration 3 --stats " +
      (out_dir() / "ui_stats.json").string() + " --stats-after 6 --trainee ana --db " +
      db.string() + (cache ? std::string(" --cache-dir ") + cache : std::string());
  const ShellResult r = shell(cmd);
  ASSERT_EQ(r.code, 0) << cmd << "\n" << r.output;
  const ShellResult h = shell(std::string(PHACO_BIN) + " history ana --json --db " + db.string());
  ASSERT_EQ(h.code, 0) << h.output;
  const nlohmann::json j = nlohmann::json::parse(h.output);
  ASSERT_EQ(j["records"].size(), 1u) << h.output;
  EXPECT_EQ(j["records"][0]["drill"], "capsulorhexis");
  EXPECT_TRUE(j["records"][0]["score"].is_number());
}

TEST(TrainerCliArgs, HelpAndBadInput) {
  const ShellResult help = shell(std::string(PHACO_TRAINER_BIN) + " --help");
  EXPECT_EQ(help.code, 0);
  EXPECT_NE(help.output.find("--screenshot"), std::string::npos);
  EXPECT_NE(help.output.find("--difficulty"), std::string::npos);
  for (const auto& [args, message] : std::array<std::pair<const char*, const char*>, 6>{{
           {"--drill vitrectomy", "--drill: unknown drill 'vitrectomy'"},
           {"--size 12", "--size: expected WxH"},
           {"--bogus", "unknown option '--bogus'"},
           {"--drill capsulorhexis --difficulty nightmare", "unknown level 'nightmare'"},
           {"--scenario /nonexistent.json", "/nonexistent.json: scenario file not found"},
           {"--ui-state /tmp/never.json --no-ui", "--ui-state: not with --no-ui"},
       }}) {
    // Bad input is refused before any window opens: no display needed.
    const ShellResult r = shell("env -u DISPLAY " + std::string(PHACO_TRAINER_BIN) + " " + args);
    EXPECT_EQ(r.code, 2) << args << "\n" << r.output;
    EXPECT_NE(r.output.find(message), std::string::npos) << args << "\n" << r.output;
  }
  // No display and no Xvfb: a clear message, exit 3, not a crash.
  const ShellResult none =
      shell("env -u DISPLAY -u WAYLAND_DISPLAY " + std::string(PHACO_TRAINER_BIN) +
            " --drill capsulorhexis --screenshot /tmp/never.png");
  EXPECT_EQ(none.code, 3) << none.output;
  EXPECT_NE(none.output.find("cannot open a display"), std::string::npos) << none.output;
}

}  // namespace
}  // namespace phaco
