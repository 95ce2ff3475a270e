// The trainer's settings between runs (issue 23): saved to and read from the XDG config folder,
// filling only what the command line leaves out; a damaged file and an unwritable folder are named.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "apps/trainer/trainer_settings.hpp"
#include "engine/core/error.hpp"

namespace {

namespace fs = std::filesystem;
using namespace phaco::trainer;

fs::path scratch() {
  const fs::path d =
      fs::temp_directory_path() / ("phaco-trainer-settings-" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

TEST(TrainerSettings, SavedSettingsComeBack) {
  const fs::path dir = scratch();
  const fs::path file = dir / "openphaco" / "trainer.json";
  EXPECT_TRUE(load_trainer_settings(file).trainee.empty()) << "never saved: empty";
  save_trainer_settings(
      file, {"Ana Ruiz", "scripted", "udp:9000@127.0.0.1:9001", "phaco_sculpting", "hard"});
  const TrainerSettings s = load_trainer_settings(file);
  EXPECT_EQ(s.trainee, "Ana Ruiz");
  EXPECT_EQ(s.left, "scripted");
  EXPECT_EQ(s.right, "udp:9000@127.0.0.1:9001");
  EXPECT_EQ(s.drill, "phaco_sculpting");
  EXPECT_EQ(s.difficulty, "hard");

  ::setenv("XDG_CONFIG_HOME", dir.c_str(), 1);
  EXPECT_EQ(trainer_settings_file(), file);
  ::unsetenv("XDG_CONFIG_HOME");
  fs::remove_all(dir);
}

TEST(TrainerSettings, TheCommandLineWins) {
  const TrainerSettings s{"Ana Ruiz", "scripted", "track", "phaco_sculpting", "hard"};
  TrainerOptions o = parse_options({"--right", "desktop"});
  apply_trainer_settings(o, s, {"--right", "desktop"});
  EXPECT_EQ(o.trainee, "Ana Ruiz");
  EXPECT_EQ(o.left, "scripted");
  EXPECT_EQ(o.right, "desktop");
  EXPECT_EQ(o.scenario, drill_scenario("phaco_sculpting"));
  EXPECT_EQ(o.difficulty, "hard");

  TrainerOptions given = parse_options({"--drill", "corneal_incision", "--trainee", "Bo"});
  apply_trainer_settings(given, s, {"--drill", "corneal_incision", "--trainee", "Bo"});
  EXPECT_EQ(given.trainee, "Bo");
  EXPECT_EQ(given.scenario, drill_scenario("corneal_incision"));
  EXPECT_EQ(given.difficulty, "") << "a level belongs to its drill: not carried to another";
}

TEST(TrainerSettings, DamageAndUnwritableFoldersAreNamed) {
  const fs::path dir = scratch();
  std::ofstream(dir / "trainer.json") << R"({"trainee": 3})";
  try {
    load_trainer_settings(dir / "trainer.json");
    FAIL() << "expected InputError";
  } catch (const phaco::InputError& e) {
    EXPECT_NE(std::string(e.what()).find((dir / "trainer.json").string() + ": /trainee"),
              std::string::npos)
        << e.what();
  }
  std::ofstream(dir / "file") << "x";
  try {
    save_trainer_settings(dir / "file" / "openphaco" / "trainer.json", {});
    FAIL() << "expected InputError";
  } catch (const phaco::InputError& e) {
    EXPECT_NE(
        std::string(e.what()).find("cannot write to " + (dir / "file" / "openphaco").string()),
        std::string::npos)
        << e.what();
  }
  fs::remove_all(dir);
}

}  // namespace
