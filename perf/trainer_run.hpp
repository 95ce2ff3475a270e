#pragma once
// One phaco-trainer run under Xvfb with --stats, as a trainee starts it (phaco-perf trainer and
// trainer-ab): the binary, the scripted hands, the window size, and the figures it writes.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

namespace phaco::perf {

constexpr int kTrainerWidth = 1280, kTrainerHeight = 720;

struct TrainerRun {
  std::string drill;  // or "procedure"
  bool render = true;
  nlohmann::json stats;
  double load_before = -1, load_after = -1;  // 1-min load average: the machine may be shared
};

// phaco-trainer beside this executable's build: <build>/perf/phaco-perf → <build>/apps/.
std::filesystem::path trainer_binary();

double load_1min();

// The CPU the trainer's drawing took per frame, read from /proc while it ran: its main thread
// (the GL calls, the UI) and Mesa's llvmpipe threads (rasterising), over the steady part of the
// measured window (its first 3 s skipped). CPU time per frame moves much less than the frame rate
// when other processes share the cores, so it tells two builds apart under load.
struct RenderCpu {
  double main_ms = 0, llvmpipe_ms = 0, other_ms = 0;  // per frame; other: every other thread
  double window_s = 0;
  bool measured = false;
};

// Runs `bin` with `what` ("--drill NAME" or "--procedure FILE") and `tail` (how long, other
// options) under xvfb-run; `data_dir`, when given, is the PHACO_DATA_DIR the binary reads (an
// older build's own data). `name` names the stats file in `dir`. Throws InputError when the run
// fails or writes no figures.
TrainerRun run_trainer(const std::filesystem::path& bin, const std::filesystem::path& dir,
                       const std::string& name, const std::string& what, const std::string& tail,
                       bool render, const std::optional<std::filesystem::path>& data_dir = {},
                       RenderCpu* cpu = nullptr);

// A drill for `seconds` of measurement after the drill has run as long (the scripted hands then
// hold their last pose).
TrainerRun run_trainer_drill(const std::filesystem::path& bin, const std::filesystem::path& dir,
                             const std::string& drill, bool render, double seconds,
                             const std::optional<std::filesystem::path>& data_dir = {},
                             const std::string& name = {}, RenderCpu* cpu = nullptr);

}  // namespace phaco::perf
