#pragma once
// What phaco-trainer draws over the microscope view for a trainee (issue 24 items 2 and 4): each
// tip's height above the tissue under it, in colour, next to the tip; and the controls of the
// drill's tools, shown on the first start of each drill and again on F1.
#include <imgui.h>

#include <string>

#include "engine/io/scenario.hpp"
#include "engine/render/renderer.hpp"
#include "engine/render/snapshot.hpp"

namespace phaco::trainer {

ImVec4 hand_colour(Hand hand);
// Above the tissue: green; touching it: amber; in it: red; over no tissue: grey.
ImVec4 height_colour(double height_mm);
// "0.85 mm above capsule", "touching lens", "0.30 mm in cornea", "over no tissue".
std::string height_text(const render::ToolView& tool);

// Each tool's height as a label beside its tip (mono view of width × height px).
void draw_height_labels(const render::RenderSnapshot& snap, const render::Microscope& microscope,
                        int width, int height);

// The drill's controls, centred over the view; the window's close button and "Got it" clear
// `open`.
void controls_window(const Scenario& scenario, bool& open);

}  // namespace phaco::trainer
