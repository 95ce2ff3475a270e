#pragma once
// phaco-trainer's main thread (issue 8; DESIGN.md §5): the GLFW window, the OpenGL renderer of
// the newest simulation snapshot, Dear ImGui's panels, and mouse/keyboard/gamepad fed to the
// session's DesktopInput. The simulation and the 1 kHz haptic loop run on their own threads in
// TrainerSession (procedures/trainer); this thread only reads their newest snapshot and status, so
// a slow frame here never slows them (docs/trainer_threads.md).
#include "apps/trainer/trainer_options.hpp"

namespace phaco::trainer {

// Runs until the window closes (or the unattended mode is done). Returns the exit code. Throws
// InputError (bad scenario, device, trainee) and render::RenderError (no display, no GL 3.3).
int run_trainer(const TrainerOptions& options);

}  // namespace phaco::trainer
