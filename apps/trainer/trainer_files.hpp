#pragma once
// What phaco-trainer writes beside its window: JSON files written whole (--ui-state, --stats,
// a saved view's poses) and F12's saved views (docs/trainer.md). Main thread only (GL context).
#include <filesystem>
#include <nlohmann/json.hpp>

#include "engine/render/renderer.hpp"

namespace phaco::trainer {

// Writes `j` to `file` whole or not at all (a reader never sees half a file); throws InputError
// naming `what` when it cannot.
void write_json_file(const std::filesystem::path& file, const nlohmann::json& j,
                     const char* what = "the UI state");

// The view alone (no panels), drawn off-screen at w × h and saved as a PNG: a hidden or covered
// window's pixels are undefined. Leaves the window's framebuffer bound.
void save_view(render::Renderer& renderer, const render::RenderSnapshot& snap,
               const render::Microscope& microscope, int w, int h,
               const std::filesystem::path& file);

// What F12's view shows, beside its PNG: the tools' shown poses, the globe's turn and the camera,
// so the picture can be checked against the geometry (tests/apps/test_trainer_port_view.cpp).
void write_view_poses(const std::filesystem::path& file, const render::RenderSnapshot& snap,
                      const render::Microscope& m, double sim_time_s, int w, int h);

}  // namespace phaco::trainer
