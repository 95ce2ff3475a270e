#include "apps/trainer/trainer_settings.hpp"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "engine/core/error.hpp"
#include "engine/io/user_dirs.hpp"

namespace phaco::trainer {

namespace fs = std::filesystem;

namespace {

bool given(const std::vector<std::string>& args, const char* option) {
  return std::find(args.begin(), args.end(), option) != args.end();
}

}  // namespace

fs::path trainer_settings_file() {
  return io::user_dir(io::UserDir::Config) / "trainer.json";
}

TrainerSettings load_trainer_settings(const fs::path& file) {
  TrainerSettings s;
  std::ifstream in(file);
  if (!in) return s;  // never saved
  std::stringstream text;
  text << in.rdbuf();
  const nlohmann::json j = nlohmann::json::parse(text.str(), nullptr, false);
  if (!j.is_object()) throw InputError(file.string() + ": expected a JSON object");
  const auto field = [&](const char* key, std::string& out) {
    if (!j.contains(key)) return;
    if (!j[key].is_string()) throw InputError(file.string() + ": /" + key + ": expected a string");
    out = j[key].get<std::string>();
  };
  field("trainee", s.trainee);
  field("left", s.left);
  field("right", s.right);
  field("drill", s.drill);
  field("difficulty", s.difficulty);
  return s;
}

void save_trainer_settings(const fs::path& file, const TrainerSettings& s) {
  io::writable_dir(file.parent_path(), "trainer settings",
                   "set XDG_CONFIG_HOME to a writable folder");
  const nlohmann::json j = {{"trainee", s.trainee},
                            {"left", s.left},
                            {"right", s.right},
                            {"drill", s.drill},
                            {"difficulty", s.difficulty}};
  const fs::path tmp = file.string() + ".tmp";
  std::ofstream out(tmp);
  out << j.dump(2) << "\n";
  out.close();
  std::error_code ec;
  if (out) fs::rename(tmp, file, ec);  // whole or not at all
  if (!out || ec) {
    fs::remove(tmp, ec);
    throw InputError("cannot write " + file.string() + " (trainer settings)");
  }
}

bool interactive(const TrainerOptions& o) {
  return !o.screenshot && !o.stats && !o.soak;
}

void apply_trainer_settings(TrainerOptions& o, const TrainerSettings& s,
                            const std::vector<std::string>& args) {
  if (!given(args, "--trainee") && !s.trainee.empty()) o.trainee = s.trainee;
  if (!given(args, "--left") && !s.left.empty()) o.left = s.left;
  if (!given(args, "--right") && !s.right.empty()) o.right = s.right;
  const bool drill_given = given(args, "--drill") || given(args, "--scenario");
  if (!drill_given && !s.drill.empty()) o.scenario = drill_scenario(s.drill);
  if (!drill_given && !given(args, "--difficulty")) o.difficulty = s.difficulty;
}

void recall_settings(TrainerOptions& o, const std::vector<std::string>& args) {
  fs::path file;
  try {
    file = trainer_settings_file();
    apply_trainer_settings(o, load_trainer_settings(file), args);
  } catch (const InputError& e) {
    std::fprintf(stderr, "phaco-trainer: saved settings ignored: %s\n", e.what());
  }
}

void remember_settings(const TrainerOptions& o, const TrainerConfig& c) {
  if (!interactive(o)) return;
  try {
    save_trainer_settings(trainer_settings_file(),
                          {c.trainee, c.devices[0], c.devices[1],
                           std::string(to_string(c.scenario.drill)), c.scenario.difficulty});
  } catch (const InputError& e) {
    std::fprintf(stderr, "phaco-trainer: settings not saved: %s\n", e.what());
  }
}

}  // namespace phaco::trainer
