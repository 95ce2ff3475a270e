#include "apps/trainer/trainer_ui.hpp"

#include <imgui.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "apps/trainer/trainer_overlays.hpp"
#include "engine/core/error.hpp"
#include "engine/records/background_sync.hpp"
#include "engine/records/record_location.hpp"
#include "engine/records/record_run.hpp"
#include "engine/records/records.hpp"
#include "procedures/report/html_report.hpp"
#include "procedures/report/report_fields.hpp"
#include "procedures/scene/scene.hpp"

namespace phaco::trainer {

namespace {

constexpr std::array<const char*, 4> kDrills = {"corneal_incision", "capsulorhexis",
                                                "phaco_sculpting", "nucleus_removal"};
constexpr std::array<const char*, 3> kDevices = {"desktop", "scripted", "track"};
constexpr std::array<const char*, 4> kStates = {"idle", "running", "paused",
                                                "ended"};  // TrainerState

// Events a trainee must notice at once (seed 004: warn before the tear runs out).
bool is_warning(const std::string& kind) {
  return kind == "runout_warning" || kind == "radial_tearout" || kind == "capsule_breach" ||
         kind == "posterior_capsule_rupture" || kind == "corneal_stress" || kind == "port_stress" ||
         kind == "iris_contact" || kind == "lens_contact";
}

int index_of(const std::vector<std::string>& names, const std::string& name) {
  const auto it = std::find(names.begin(), names.end(), name);
  return it == names.end() ? 0 : static_cast<int>(it - names.begin());
}

}  // namespace

TrainerUi::TrainerUi(const TrainerOptions& options, const TrainerConfig& config)
    : options_(options), config_(config) {
  for (size_t i = 0; i < kDrills.size(); ++i)
    if (to_string(config.scenario.drill) == kDrills[i]) drill_index_ = static_cast<int>(i);
  for (int h = 0; h < 2; ++h)
    for (size_t i = 0; i < kDevices.size(); ++i)
      if (config.devices[static_cast<size_t>(h)] == kDevices[i])
        device_index_[h] = static_cast<int>(i);
  std::snprintf(trainee_, sizeof trainee_, "%s", config.trainee.c_str());
  refresh_levels();
  level_index_ = index_of(levels_, config.scenario.difficulty.empty()
                                       ? load_drill_for(config.scenario).default_difficulty
                                       : config.scenario.difficulty);
}

void TrainerUi::refresh_levels() {
  levels_.clear();
  for (const auto& [name, unused] : load_drill_for(config_.scenario).difficulty)
    levels_.push_back(name);
  level_index_ = std::min<int>(level_index_, static_cast<int>(levels_.size()) - 1);
}

UiAction TrainerUi::draw(TrainerSession& session, render::Renderer& renderer,
                         render::Microscope& microscope, double frame_ms,
                         const render::RenderSnapshot* snap, int view_w, int view_h) {
  UiAction action = UiAction::None;
  // A drill that reached its end is finished once: its score and report appear.
  if (session.state() == TrainerState::Ended && !finished_) finish(session);
  // The first start of each drill names its controls (F1 shows them again); not in the unattended
  // runs, which nobody reads and whose frame rate is the steady view's.
  const bool unattended = options_.screenshot || options_.stats || options_.soak;
  if (intro_seen_.insert(std::string(to_string(session.config().scenario.drill))).second)
    controls_open_ = !unattended;
  if (snap && renderer.options().stereo == render::StereoMode::Mono)
    draw_height_labels(*snap, microscope, view_w, view_h);
  drill_panel(session, action);
  live_panel(session, frame_ms, snap);
  result_panel(session);
  history_panel();
  view_panel(renderer, microscope);
  if (controls_open_) controls_window(session.config().scenario, controls_open_);
  return action;
}

void TrainerUi::finish(TrainerSession& session) {
  finished_ = true;  // once, also when it fails: the message says why
  try {
    report_ = session.finish();
    if (report_.contains("save_error"))
      message_ = "NOT STORED: " + report_["save_error"].get<std::string>() +
                 ". The drill is kept: fix the cause and press 'Save again'.";
    else
      message_ = report_.contains("record_id") ? "stored as record " + report_["record_id"].dump()
                                               : std::string("finished (not stored: no trainee)");
    if (sync_ && report_.contains("record_id")) sync_->request();
    rows_.clear();
    for (const report::fields::Term& t : report::fields::read_run(report_).terms)
      rows_.push_back(report::term_text(t));
  } catch (const InputError& e) {
    message_ = e.what();
  }
}

void TrainerUi::drill_panel(TrainerSession& session, UiAction& action) {
  ImGui::SetNextWindowPos(ImVec2(10, 10), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(340, 0), ImGuiCond_FirstUseEver);
  ImGui::Begin("Drill");
  ImGui::InputText("trainee", trainee_, sizeof trainee_);
  if (ImGui::Combo("drill", &drill_index_, kDrills.data(), static_cast<int>(kDrills.size()))) {
    try {
      config_.scenario = load_scenario(drill_scenario(kDrills[static_cast<size_t>(drill_index_)]));
      refresh_levels();
      level_index_ = index_of(levels_, load_drill_for(config_.scenario).default_difficulty);
    } catch (const InputError& e) {
      message_ = e.what();
    }
  }
  std::vector<const char*> names;
  for (const auto& l : levels_) names.push_back(l.c_str());
  ImGui::Combo("difficulty", &level_index_, names.data(), static_cast<int>(names.size()));
  ImGui::Combo("left hand", &device_index_[0], kDevices.data(), static_cast<int>(kDevices.size()));
  ImGui::Combo("right hand", &device_index_[1], kDevices.data(), static_cast<int>(kDevices.size()));
  if (ImGui::Button("Start new drill")) {
    config_.scenario.difficulty = levels_.empty() ? "" : levels_[static_cast<size_t>(level_index_)];
    config_.devices = {kDevices[static_cast<size_t>(device_index_[0])],
                       kDevices[static_cast<size_t>(device_index_[1])]};
    config_.trainee = trainee_;
    finished_ = false;
    report_ = nlohmann::json();
    events_.clear();
    action = UiAction::Restart;
  }
  ImGui::SameLine();
  const TrainerState state = session.state();
  if (state == TrainerState::Paused) {
    if (ImGui::Button("Resume")) session.resume();
  } else if (ImGui::Button("Pause")) {
    session.pause();
  }
  ImGui::SameLine();
  if (ImGui::Button("Restart")) {
    finished_ = false;
    events_.clear();
    session.reset();
  }
  if (ImGui::Button("Finish") && state != TrainerState::Idle && !finished_) finish(session);
  ImGui::SameLine();
  if (ImGui::Button("Replay last")) {
    try {
      session.replay_last();
      finished_ = false;
      events_.clear();
    } catch (const InputError& e) {
      message_ = e.what();
    }
  }
  if (!message_.empty()) ImGui::TextWrapped("%s", message_.c_str());
  ImGui::PushStyleColor(ImGuiCol_Text, ImGui::GetStyleColorVec4(ImGuiCol_TextDisabled));
  ImGui::TextWrapped(
      "Tab: other hand  Space: pause  R: restart  G: guidance  F1: controls  F12: save view");
  ImGui::PopStyleColor();
  ImGui::End();
}

void TrainerUi::live_panel(TrainerSession& session, double frame_ms,
                           const render::RenderSnapshot* snap) {
  const TrainerStatus s = session.status();
  polled_.clear();
  session.poll_events(polled_);
  for (const TrainerEvent& e : polled_) {
    std::string text = e.kind;
    if (e.hand >= 0) text += e.hand == 0 ? " (left)" : " (right)";
    if (e.detail) {
      char buf[64];
      std::snprintf(buf, sizeof buf, " %s %.2f", e.detail, e.value);
      text += buf;
    }
    events_.push_front({e.t_s, text, is_warning(e.kind)});
    if (events_.size() > 12) events_.pop_back();
  }
  ImGui::SetNextWindowPos(ImVec2(10, 260), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(360, 220), ImGuiCond_FirstUseEver);
  ImGui::Begin("Live");
  ImGui::Text("%s  %.1f / %.1f s", kStates[static_cast<size_t>(s.state)], s.sim_time_s,
              s.duration_s);
  ImGui::Text("simulation %.0f Hz   render %.0f fps", s.sim_rate_hz,
              frame_ms > 0 ? 1000.0 / frame_ms : 0.0);
  ImGui::Text("haptics p50 %.0f us  p99 %.0f us", s.haptic_period_p50_us, s.haptic_period_p99_us);
  // Each tool: the active one as a badge in its hand's colour, its height readout in colour.
  const Hand active = session.desktop().selected();
  if (snap) {
    for (const render::ToolView& t : snap->tools) {
      const std::string name =
          std::string(to_string(t.hand)) + " " + std::string(to_string(t.kind));
      if (t.hand == active) {
        ImGui::PushStyleColor(ImGuiCol_Button, hand_colour(t.hand));
        ImGui::PushStyleColor(ImGuiCol_ButtonHovered, hand_colour(t.hand));
        ImGui::PushStyleColor(ImGuiCol_ButtonActive, hand_colour(t.hand));
        ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(0, 0, 0, 1));
        ImGui::SmallButton((name + " (mouse)").c_str());
        ImGui::PopStyleColor(4);
      } else {
        ImGui::TextColored(hand_colour(t.hand), "%s", name.c_str());
      }
      ImGui::SameLine();
      ImGui::TextColored(height_colour(t.height_mm), "%s", height_text(t).c_str());
    }
  }
  ImGui::Separator();
  for (const Shown& e : events_) {
    if (e.warning) {
      ImGui::TextColored(ImVec4(1.0f, 0.35f, 0.3f, 1.0f), "%5.1f s  %s", e.t_s, e.text.c_str());
    } else {
      ImGui::Text("%5.1f s  %s", e.t_s, e.text.c_str());
    }
  }
  ImGui::End();
}

void TrainerUi::result_panel(TrainerSession& session) {
  if (!finished_ || !report_.is_object()) return;
  // Sized to its table, so no name is cut; kept inside the window.
  const ImVec2 display = ImGui::GetIO().DisplaySize;
  ImGui::SetNextWindowPos(ImVec2(display.x - 10.0f, 10), ImGuiCond_Always, ImVec2(1.0f, 0.0f));
  ImGui::Begin("Result", nullptr, ImGuiWindowFlags_AlwaysAutoResize);
  const ImVec2 at = ImGui::GetWindowPos(), size = ImGui::GetWindowSize();
  result_on_screen_ = at.x >= 0 && at.y >= 0 && at.x + size.x <= display.x + 0.5f &&
                      at.y + size.y <= display.y + 0.5f;
  // Drills whose record the database refused stay in memory until they are stored.
  if (session.unsaved_count() > 0) {
    ImGui::TextColored(ImVec4(1.0f, 0.45f, 0.3f, 1.0f), "%zu finished drill(s) not stored",
                       session.unsaved_count());
    if (ImGui::Button("Save again")) {
      try {
        const std::vector<int64_t> ids = session.save_unsaved();
        report_ = session.last_report();
        message_ = "stored " + std::to_string(ids.size()) + " drill(s), last as record " +
                   std::to_string(ids.back());
      } catch (const InputError& e) {
        message_ = std::string("still not stored: ") + e.what();
      }
    }
  }
  const auto& m = report_.value("metrics", nlohmann::json::object());
  ImGui::Text("score %.1f / 100", m.value("score", 0.0));
  // The terms as the HTML report writes them (procedures/report/term_text): names with units,
  // targets as ranges, met in green and missed in red.
  row_fits_.assign(rows_.size(), true);
  constexpr ImGuiTableFlags kFlags =
      ImGuiTableFlags_Borders | ImGuiTableFlags_RowBg | ImGuiTableFlags_SizingFixedFit;
  if (ImGui::BeginTable("terms", 4, kFlags)) {
    ImGui::TableSetupColumn("metric");
    ImGui::TableSetupColumn("value");
    ImGui::TableSetupColumn("target");
    ImGui::TableSetupColumn("points");
    ImGui::TableHeadersRow();
    for (size_t i = 0; i < rows_.size(); ++i) {
      const report::TermText& r = rows_[i];
      const ImVec4 verdict = !r.met   ? ImVec4(0.8f, 0.8f, 0.8f, 1.0f)
                             : *r.met ? ImVec4(0.35f, 0.9f, 0.4f, 1.0f)
                                      : ImVec4(1.0f, 0.35f, 0.3f, 1.0f);
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      row_fits_[i] =
          ImGui::CalcTextSize(r.label.c_str()).x <= ImGui::GetContentRegionAvail().x + 0.5f;
      ImGui::TextUnformatted(r.label.c_str());
      ImGui::TableNextColumn();
      ImGui::TextColored(verdict, "%s", r.value.c_str());
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(r.target.c_str());
      ImGui::TableNextColumn();
      // Points: green in full, red when none (a term not measured has no verdict but no points).
      const ImVec4 points = r.points == r.weight ? ImVec4(0.35f, 0.9f, 0.4f, 1.0f)
                            : r.points == "0"    ? ImVec4(1.0f, 0.35f, 0.3f, 1.0f)
                                                 : ImVec4(0.8f, 0.8f, 0.8f, 1.0f);
      ImGui::TextColored(points, "%s / %s", r.points.c_str(), r.weight.c_str());
    }
    ImGui::EndTable();
  }
  ImGui::InputText("report", report_path_, sizeof report_path_);
  if (ImGui::Button("Write HTML report")) {
    std::ofstream out(report_path_, std::ios::binary);
    out << report::html_report(report_);
    message_ = out ? std::string("report written to ") + report_path_
                   : std::string("cannot write ") + report_path_;
  }
  ImGui::End();
}

void TrainerUi::history_panel() {
  ImGui::SetNextWindowPos(ImVec2(options_.width - 390.0f, options_.height - 230.0f),
                          ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(380, 220), ImGuiCond_FirstUseEver);
  ImGui::Begin("History");
  if (ImGui::Button("Load") && trainee_[0] != '\0') {
    history_ = nlohmann::json::array();
    try {
      const std::filesystem::path db = options_.db.empty() ? default_records_db() : options_.db;
      if (is_postgres_uri(db.string()) || std::filesystem::exists(db)) {
        RecordStore store(db, OpenMode::ExistingOnly);
        for (const SessionRecord& r : store.records_of(trainee_)) {
          history_.push_back({{"date", r.finished_utc.substr(0, 16)},
                              {"drill", r.drill},
                              {"score", r.score ? *r.score : -1.0}});
        }
      }
    } catch (const InputError& e) {
      message_ = e.what();
    }
  }
  ImGui::SameLine();
  ImGui::TextDisabled("%s", trainee_[0] ? trainee_ : "(no trainee)");
  if (sync_) ImGui::TextWrapped("%s", sync_->status().c_str());
  for (const auto& h : history_) {
    ImGui::Text("%s  %-16s  %5.1f", h["date"].get<std::string>().c_str(),
                h["drill"].get<std::string>().c_str(), h["score"].get<double>());
  }
  ImGui::End();
}

void TrainerUi::view_panel(render::Renderer& renderer, render::Microscope& microscope) {
  ImGui::SetNextWindowPos(ImVec2(10, options_.height - 150.0f), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(300, 0), ImGuiCond_FirstUseEver);
  ImGui::Begin("Microscope");
  float field = static_cast<float>(microscope.field_mm);
  if (ImGui::SliderFloat("field (mm)", &field, 6.0f, 26.0f)) microscope.field_mm = field;
  float focus = static_cast<float>(microscope.focus_z_mm);
  if (ImGui::SliderFloat("focus z (mm)", &focus, -2.0f, 5.0f)) microscope.focus_z_mm = focus;
  ImGui::Checkbox("guidance cues", &renderer.options().guidance);
  bool stereo = renderer.options().stereo == render::StereoMode::SideBySide;
  if (ImGui::Checkbox("side-by-side stereo", &stereo))
    renderer.options().stereo = stereo ? render::StereoMode::SideBySide : render::StereoMode::Mono;
  ImGui::End();
}

nlohmann::json TrainerUi::state_json(TrainerSession& session,
                                     const render::RenderSnapshot* snap) const {
  const TrainerStatus st = session.status();
  nlohmann::json j;
  j["state"] = kStates[static_cast<size_t>(st.state)];
  j["sim_time_s"] = st.sim_time_s;
  j["drill"] = std::string(to_string(session.config().scenario.drill));
  j["active_hand"] = std::string(to_string(session.desktop().selected()));
  j["controls_shown"] = controls_open_;
  j["tools"] = nlohmann::json::array();
  if (snap) {
    for (const render::ToolView& t : snap->tools) {
      j["tools"].push_back({{"hand", std::string(to_string(t.hand))},
                            {"tool", std::string(to_string(t.kind))},
                            {"tip_mm", {t.tip_mm.x(), t.tip_mm.y(), t.tip_mm.z()}},
                            {"height_mm", std::isfinite(t.height_mm) ? nlohmann::json(t.height_mm)
                                                                     : nlohmann::json()},
                            {"readout", height_text(t)},
                            {"selected", t.selected}});
    }
  }
  if (finished_ && report_.is_object()) {
    nlohmann::json rows = nlohmann::json::array();
    for (size_t i = 0; i < rows_.size(); ++i) {
      const report::TermText& r = rows_[i];
      rows.push_back({{"metric", r.label},
                      {"value", r.value},
                      {"target", r.target},
                      {"points", r.points + " / " + r.weight},
                      {"met", r.met ? nlohmann::json(*r.met) : nlohmann::json()},
                      {"name_fits", i < row_fits_.size() && row_fits_[i]}});
    }
    j["result"] = {{"rows", rows},
                   {"on_screen", result_on_screen_},
                   {"metrics", report_.value("metrics", nlohmann::json::object())}};
  }
  return j;
}

}  // namespace phaco::trainer
