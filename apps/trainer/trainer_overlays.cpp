#include "apps/trainer/trainer_overlays.hpp"

#include <cmath>
#include <cstdio>

#include "procedures/trainer/tip_height.hpp"

namespace phaco::trainer {

namespace {

const char* tissue_name(render::Tissue t) {
  switch (t) {
    case render::Tissue::Cornea:
      return "cornea";
    case render::Tissue::Capsule:
      return "capsule";
    case render::Tissue::Lens:
      return "lens";
    case render::Tissue::None:
      break;
  }
  return "tissue";
}

// What the mouse buttons do with this tool (desktop_input.hpp's map_buttons).
const char* buttons_of(ToolKind tool) {
  switch (tool) {
    case ToolKind::PhacoProbe:
    case ToolKind::Aspirator:
      return "left button: ultrasound (pedal 3), right button: aspiration (pedal 2)";
    case ToolKind::Forceps:
      return "left button: close the jaws (grasp), release to let go";
    default:
      return "buttons: none (the blade cuts where the tip goes)";
  }
}

}  // namespace

ImVec4 hand_colour(Hand hand) {
  return hand == Hand::Left ? ImVec4(0.25f, 0.55f, 1.0f, 1.0f) : ImVec4(1.0f, 0.6f, 0.15f, 1.0f);
}

ImVec4 height_colour(double h) {
  switch (height_band(h)) {
    case HeightBand::Above:
      return ImVec4(0.35f, 0.9f, 0.4f, 1.0f);
    case HeightBand::Touching:
      return ImVec4(1.0f, 0.8f, 0.2f, 1.0f);
    case HeightBand::In:
      return ImVec4(1.0f, 0.3f, 0.25f, 1.0f);
    case HeightBand::None:
      break;
  }
  return ImVec4(0.7f, 0.7f, 0.7f, 1.0f);
}

std::string height_text(const render::ToolView& t) {
  char buf[64];
  switch (height_band(t.height_mm)) {
    case HeightBand::Above:
      std::snprintf(buf, sizeof buf, "%.2f mm above %s", t.height_mm, tissue_name(t.under));
      break;
    case HeightBand::Touching:
      std::snprintf(buf, sizeof buf, "%.2f mm, touching %s", t.height_mm, tissue_name(t.under));
      break;
    case HeightBand::In:
      std::snprintf(buf, sizeof buf, "%.2f mm in %s", -t.height_mm, tissue_name(t.under));
      break;
    case HeightBand::None:
      return "over no tissue";
  }
  return buf;
}

void draw_height_labels(const render::RenderSnapshot& snap, const render::Microscope& microscope,
                        int width, int height) {
  ImDrawList* dl = ImGui::GetBackgroundDrawList();
  for (const render::ToolView& t : snap.tools) {
    const auto px = render::project_to_pixel(microscope, t.tip_mm, width, height);
    if (!std::isfinite(px[0]) || !std::isfinite(px[1])) continue;
    char buf[32];
    if (std::isfinite(t.height_mm)) {
      std::snprintf(buf, sizeof buf, "%+.2f mm", t.height_mm);
    } else {
      std::snprintf(buf, sizeof buf, "--");
    }
    // The left hand's label to the left of its tip, the right hand's to the right: two tips close
    // together keep their labels apart.
    const ImVec2 size = ImGui::CalcTextSize(buf);
    const float x = static_cast<float>(px[0]);
    const ImVec2 at(t.hand == Hand::Left ? x - 14.0f - size.x : x + 14.0f,
                    static_cast<float>(px[1]) - 22.0f);
    // A dark plate keeps the label legible over the bright red reflex and the white sclera.
    dl->AddRectFilled(ImVec2(at.x - 3, at.y - 1), ImVec2(at.x + size.x + 3, at.y + size.y + 1),
                      IM_COL32(0, 0, 0, 170), 3.0f);
    dl->AddRect(ImVec2(at.x - 3, at.y - 1), ImVec2(at.x + size.x + 3, at.y + size.y + 1),
                ImGui::GetColorU32(hand_colour(t.hand)), 3.0f, 0, t.selected ? 2.0f : 1.0f);
    dl->AddText(at, ImGui::GetColorU32(height_colour(t.height_mm)), buf);
  }
}

void controls_window(const Scenario& scenario, bool& open) {
  const ImVec2 display = ImGui::GetIO().DisplaySize;
  ImGui::SetNextWindowPos(ImVec2(display.x * 0.5f, display.y * 0.5f), ImGuiCond_Appearing,
                          ImVec2(0.5f, 0.5f));
  const std::string title = "Controls: " + std::string(to_string(scenario.drill)) + "###controls";
  if (!ImGui::Begin(title.c_str(), &open, ImGuiWindowFlags_AlwaysAutoResize)) {
    ImGui::End();
    return;
  }
  for (const HandTrack& h : scenario.hands) {
    ImGui::TextColored(hand_colour(h.hand), "%s hand: %s", std::string(to_string(h.hand)).c_str(),
                       std::string(to_string(h.tool)).c_str());
    ImGui::BulletText("%s", buttons_of(h.tool));
  }
  ImGui::Separator();
  ImGui::BulletText("mouse: moves the active hand's tip across the eye (only over the view)");
  ImGui::BulletText("wheel: depth, 0.1 mm a click; forward goes deeper");
  ImGui::BulletText("Tab: the other hand becomes active (the badge in the Live panel)");
  ImGui::BulletText("clutch: hold the middle button or Shift to move the pointer, not the tool;");
  ImGui::TextUnformatted("    over a panel or outside the window both tools stay where they are");
  ImGui::BulletText("the label by each tip: its height above the tissue under it");
  ImGui::BulletText(
      "Space: pause   R: restart   G: guidance cues   F1: this help   F12: save the view   Esc: "
      "quit");
  ImGui::BulletText("gamepad: sticks move the tips, LB/RB deeper, stick clicks up, triggers grip");
  if (ImGui::Button("Got it (F1 shows this again)")) open = false;
  ImGui::End();
}

}  // namespace phaco::trainer
