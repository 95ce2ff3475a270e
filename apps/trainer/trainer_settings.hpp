#pragma once
// The trainer's settings between runs (issue 23): the last trainee, each hand's device, the drill
// and its level, in $XDG_CONFIG_HOME/openphaco/trainer.json (default ~/.config/openphaco). Only an
// interactive run reads and writes them: unattended runs (--screenshot, --stats, --soak) take the
// command line alone, so the tests and the perf harness never depend on a user's last choices.
#include <filesystem>
#include <string>
#include <vector>

#include "apps/trainer/trainer_options.hpp"
#include "procedures/trainer/trainer_session.hpp"

namespace phaco::trainer {

struct TrainerSettings {
  std::string trainee, left, right, drill, difficulty;  // "" = not saved
};

// user_dir(Config) / "trainer.json" (engine/io/user_dirs.hpp).
std::filesystem::path trainer_settings_file();

// No file: empty settings. Throws InputError naming the file and the field for a damaged one.
TrainerSettings load_trainer_settings(const std::filesystem::path& file);
// Throws InputError naming the folder that cannot be written.
void save_trainer_settings(const std::filesystem::path& file, const TrainerSettings& s);

bool interactive(const TrainerOptions& o);

// Fills from `s` what the command line `args` did not give (--trainee, --left, --right, --drill
// or --scenario, --difficulty).
void apply_trainer_settings(TrainerOptions& o, const TrainerSettings& s,
                            const std::vector<std::string>& args);

// An interactive run: options completed from the saved settings; a damaged file is named on
// stderr and ignored. Saves what the run ended with; a failure is named on stderr, not fatal.
void recall_settings(TrainerOptions& o, const std::vector<std::string>& args);
void remember_settings(const TrainerOptions& o, const TrainerConfig& c);

}  // namespace phaco::trainer
