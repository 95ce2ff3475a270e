#pragma once
// phaco-trainer's command line (issue 8): which drill, how hard, which device per hand, who
// trains, the window, and the unattended modes the tests and the perf harness use (a screenshot
// after some simulated seconds; statistics after a while).
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace phaco::trainer {

struct TrainerOptions {
  std::filesystem::path scenario;                   // the drill's layout and tracks
  std::string difficulty;                           // a level of the drill file ("" = its default)
  std::string left = "desktop", right = "desktop";  // device per hand (TrainerSession specs)
  std::string trainee;                              // records the finished drill when set
  std::filesystem::path db;                         // records database ("" = the default)
  // A training centre's server (postgresql:// URI; --sync-to or $PHACO_SYNC_TO): the station's
  // records are uploaded to it in the background after each stored drill ("" = no sync).
  std::string sync_to;
  int width = 1280, height = 720;
  bool stereo = false, guidance = true, ui = true, render = true;
  int threads = 1;
  // Simulated seconds before the drill ends by itself; 0: the scenario's duration when every
  // hand plays its script (scripted, track, replay), else 15 minutes for a trainee.
  double duration_s = 0;
  std::optional<std::filesystem::path> cache_dir;
  // Unattended: after `after_s` simulated seconds, save the view (no UI) and exit.
  std::optional<std::filesystem::path> screenshot;
  double after_s = 5.0;
  // Unattended: after `stats_after_s` wall seconds, write frame statistics as JSON and exit.
  std::optional<std::filesystem::path> stats;
  double stats_after_s = 20.0;
  double timeout_s = 600.0;  // unattended modes give up (exit 3) after this many wall seconds
  // Unattended soak (issue 18): drill after drill (the three drills in turn, scripted hands) for
  // `soak_for_s` wall seconds, then the per-drill samples (memory, GL objects, haptic period) as
  // JSON to `soak` (apps/trainer/trainer_soak.hpp).
  std::optional<std::filesystem::path> soak;
  // What the trainee sees (TrainerUi::state_json), rewritten ten times a second while running.
  std::optional<std::filesystem::path> ui_state;
  // Where F12 saves the view (view-NNN.png, and view-NNN.json with the poses it shows).
  std::filesystem::path views_dir = ".";
  double soak_for_s = 60.0;
  // The procedure mode (apps/trainer/trainer_procedure.hpp): the procedure file, and where its
  // recording and report go when it is done.
  std::optional<std::filesystem::path> procedure, procedure_out;
};

extern const char* const kUsage;

// Parses argv (without the program name). Throws InputError naming the option.
TrainerOptions parse_options(const std::vector<std::string>& args);

// The default scenario of a drill name ("corneal_incision", "capsulorhexis", "phaco_sculpting",
// or the short "incision", "rhexis", "sculpting"): data/scenarios/<drill>_expert.json, whose
// tracks give the tools and their starting poses.
std::filesystem::path drill_scenario(const std::string& drill);

}  // namespace phaco::trainer
