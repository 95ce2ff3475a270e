// phaco-trainer — the trainee's executable (issue 8): a real-time 3D microscope view of the eye,
// two-handed control from mouse/keyboard, gamepad or haptic devices, live warnings and the score.
// `phaco-trainer --help` lists the options; docs/trainer.md explains the rest.
#include <cstdio>
#include <string>
#include <vector>

#include "apps/trainer/trainer_app.hpp"
#include "apps/trainer/trainer_options.hpp"
#include "engine/core/error.hpp"
#include "engine/render/renderer.hpp"

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  for (const auto& a : args) {
    if (a == "--help" || a == "-h") {
      std::fputs(phaco::trainer::kUsage, stdout);
      return 0;
    }
  }
  try {
    return phaco::trainer::run_trainer(phaco::trainer::parse_options(args));
  } catch (const phaco::InputError& e) {
    std::fprintf(stderr, "phaco-trainer: %s\n", e.what());
    return 2;
  } catch (const phaco::render::RenderError& e) {
    std::fprintf(stderr, "phaco-trainer: %s\n", e.what());
    return 3;
  }
}
