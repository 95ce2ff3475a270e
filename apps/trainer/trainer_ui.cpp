#include "apps/trainer/trainer_ui.hpp"

#include <imgui.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <fstream>

#include "engine/core/error.hpp"
#include "engine/records/background_sync.hpp"
#include "engine/records/record_location.hpp"
#include "engine/records/record_run.hpp"
#include "engine/records/records.hpp"
#include "procedures/report/html_report.hpp"
#include "procedures/scene/scene.hpp"

namespace phaco::trainer {

namespace {

constexpr std::array<const char*, 4> kDrills = {"corneal_incision", "capsulorhexis",
                                                "phaco_sculpting", "nucleus_removal"};
constexpr std::array<const char*, 3> kDevices = {"desktop", "scripted", "track"};

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
                         render::Microscope& microscope, double frame_ms) {
  UiAction action = UiAction::None;
  // A drill that reached its end is finished once: its score and report appear.
  if (session.state() == TrainerState::Ended && !finished_) finish(session);
  drill_panel(session, action);
  live_panel(session, frame_ms);
  result_panel(session);
  history_panel();
  view_panel(renderer, microscope);
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
  } catch (const InputError& e) {
    message_ = e.what();
  }
}

void TrainerUi::drill_panel(TrainerSession& session, UiAction& action) {
  ImGui::SetNextWindowPos(ImVec2(10, 10), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(300, 0), ImGuiCond_FirstUseEver);
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
  ImGui::TextDisabled("Tab: other hand  Space: pause  R: restart  G: guidance");
  ImGui::End();
}

void TrainerUi::live_panel(TrainerSession& session, double frame_ms) {
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
  ImGui::SetNextWindowSize(ImVec2(300, 0), ImGuiCond_FirstUseEver);
  ImGui::Begin("Live");
  static constexpr std::array<const char*, 4> kStates = {"idle", "running", "paused", "ended"};
  ImGui::Text("%s  %.1f / %.1f s", kStates[static_cast<size_t>(s.state)], s.sim_time_s,
              s.duration_s);
  ImGui::Text("simulation %.0f Hz   render %.0f fps", s.sim_rate_hz,
              frame_ms > 0 ? 1000.0 / frame_ms : 0.0);
  ImGui::Text("haptics p50 %.0f us  p99 %.0f us", s.haptic_period_p50_us, s.haptic_period_p99_us);
  ImGui::Text("mouse drives the %s hand",
              session.desktop().selected() == Hand::Left ? "left" : "right");
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
  ImGui::SetNextWindowPos(ImVec2(options_.width - 390.0f, 10), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(380, 0), ImGuiCond_FirstUseEver);
  ImGui::Begin("Result");
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
  if (ImGui::BeginTable("terms", 4, ImGuiTableFlags_Borders | ImGuiTableFlags_RowBg)) {
    ImGui::TableSetupColumn("metric");
    ImGui::TableSetupColumn("value");
    ImGui::TableSetupColumn("target");
    ImGui::TableSetupColumn("points");
    ImGui::TableHeadersRow();
    for (const auto& t : report_.value("score_terms", nlohmann::json::array())) {
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(t.value("metric", "").c_str());
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(
          t["value"].is_number() ? std::to_string(t["value"].get<double>()).c_str() : "-");
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(t.value("target", nlohmann::json::object()).dump().c_str());
      ImGui::TableNextColumn();
      ImGui::Text("%.1f / %.0f", t.value("points", 0.0), t.value("weight", 0.0));
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

}  // namespace phaco::trainer
