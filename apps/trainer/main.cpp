// phaco-trainer — the trainee's executable (issue 8): a real-time 3D microscope view of the eye,
// two-handed control from mouse/keyboard, gamepad or haptic devices, live warnings and the score.
// `phaco-trainer --help` lists the options; docs/trainer.md explains the rest.
#include <cstdio>
#include <string>
#include <vector>

#include "apps/phaco/version_text.hpp"
#include "apps/trainer/trainer_app.hpp"
#include "apps/trainer/trainer_options.hpp"
#include "apps/trainer/trainer_settings.hpp"
#include "engine/core/error.hpp"
#include "engine/render/renderer.hpp"

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  for (const auto& a : args) {
    if (a == "--help" || a == "-h") {
      std::fputs(phaco::trainer::kUsage, stdout);
      return 0;
    }
    if (a == "--version") {
      std::fputs(phaco::cli::version_text("phaco-trainer").c_str(), stdout);
      return 0;
    }
  }
  try {
    phaco::trainer::TrainerOptions options = phaco::trainer::parse_options(args);
    // The last trainee, devices and drill, for what the command line does not say.
    if (phaco::trainer::interactive(options)) phaco::trainer::recall_settings(options, args);
    return phaco::trainer::run_trainer(options);
  } catch (const phaco::InputError& e) {
    std::fprintf(stderr, "phaco-trainer: %s\n", e.what());
    return 2;
  } catch (const phaco::render::RenderError& e) {
    std::fprintf(stderr, "phaco-trainer: %s\n", e.what());
    return 3;
  }
}
