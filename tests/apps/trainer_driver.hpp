#pragma once
// phaco-trainer driven as a trainee would drive it (tests/apps): a bash script under Xvfb moves a
// synthetic pointer and presses keys with xdotool, and reads the trainer's --ui-state file.
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "tests/support/environment.hpp"
#include "tests/support/shell.hpp"

// In a test's body: skips where a driven trainer cannot run, under ASan (a real-time drill on
// llvmpipe; the Release pass runs it) or without xvfb-run and xdotool.
#if defined(__SANITIZE_ADDRESS__)
#define PHACO_REQUIRE_TRAINER_DRIVER() \
  GTEST_SKIP() << "a real-time drill under ASan and llvmpipe; the Release pass runs it"
#else
#define PHACO_REQUIRE_TRAINER_DRIVER()                                           \
  PHACO_REQUIRE_ENVIRONMENT(                                                     \
      phaco::test::shell("command -v xvfb-run && command -v xdotool").code == 0, \
      "xvfb-run or xdotool not found (scripts/install-deps.sh installs them)")
#endif

namespace phaco::test {

// The script's helpers. It starts the trainer itself, in the background with --ui-state
// "$D/state.json" and its output in "$D/trainer.log", its PID in P; then
//   started        waits until the state says the drill runs (fails if the trainer exited first)
//   wait_for TEXT  waits (30 s at most) until the state contains TEXT: a step is taken when the
//                  state shows it (a software-rendered frame under load may take a second)
inline constexpr const char* kDriverFunctions = R"(
started() {
  for i in $(seq 1200); do
    grep -qs '"state": "running"' "$D/state.json" && return 0
    kill -0 $P 2>/dev/null || { echo "the trainer exited early"; cat "$D/trainer.log"; exit 1; }
    sleep 0.1
  done
}
wait_for() {
  for i in $(seq 300); do grep -qs "$1" "$D/state.json" && return 0; sleep 0.1; done
  echo "timed out waiting for $1"
}
)";

// Runs `steps` (bash, `set -u`; T = `trainer`, D = `dir`, "$@" = `args` and --cache-dir
// $PHACO_CACHE_DIR when set) under xvfb-run on a 1280×800 screen. The output starts with the
// command.
inline ShellResult drive_trainer(const std::string& trainer, const std::filesystem::path& dir,
                                 const std::string& steps, const std::string& args = "") {
  std::ofstream(dir / "steps.sh") << "set -u\nT=\"$1\"; D=\"$2\"; shift 2\n"
                                  << kDriverFunctions << steps;
  const char* cache = std::getenv("PHACO_CACHE_DIR");
  const std::string cmd = "xvfb-run -a -s '-screen 0 1280x800x24' bash " +
                          (dir / "steps.sh").string() + " " + trainer + " " + dir.string() +
                          (args.empty() ? "" : " " + args) +
                          (cache ? std::string(" --cache-dir ") + cache : std::string());
  ShellResult r = shell(cmd);
  r.output = cmd + "\n" + r.output;
  return r;
}

}  // namespace phaco::test
