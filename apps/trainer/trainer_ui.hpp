#pragma once
// phaco-trainer's panels (Dear ImGui; issue 8 item 2): choose trainee, drill, difficulty and
// devices; start, pause, restart, finish, replay the last run; live status and warnings as they
// happen (run-out, radial tear-out, capsule breach, corneal stress, port stress); the score and
// its terms at the end, written as the HTML report on request; the trainee's past sessions from
// the records database; the microscope's zoom and focus, guidance and stereo.
#include <deque>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "apps/trainer/trainer_options.hpp"
#include "engine/render/renderer.hpp"
#include "procedures/report/term_text.hpp"
#include "procedures/trainer/trainer_session.hpp"

namespace phaco {
class BackgroundSync;
}

namespace phaco::trainer {

enum class UiAction { None, Restart };  // Restart: build a new session from config()

class TrainerUi {
 public:
  TrainerUi(const TrainerOptions& options, const TrainerConfig& config);

  // One frame of panels (between ImGui::NewFrame and ImGui::Render). `frame_ms`: the last
  // render frame's duration; `snap`: the snapshot drawn this frame (may be null), in a view of
  // view_w × view_h px.
  UiAction draw(TrainerSession& session, render::Renderer& renderer, render::Microscope& microscope,
                double frame_ms, const render::RenderSnapshot* snap, int view_w, int view_h);
  void toggle_controls() { controls_open_ = !controls_open_; }  // F1
  // What a trainee sees, as JSON (--ui-state; the tests read it): the active hand, each tool's
  // tip and height readout, whether the controls are shown, the Result table as shown.
  nlohmann::json state_json(TrainerSession& session, const render::RenderSnapshot* snap) const;
  // The configuration the user chose (after Restart).
  const TrainerConfig& config() const { return config_; }
  // The background upload to a centre (--sync-to), asked after each stored drill; may be null.
  void set_sync(BackgroundSync* sync) { sync_ = sync; }

 private:
  void finish(TrainerSession& session);  // the drill's report (and record), once
  void drill_panel(TrainerSession& session, UiAction& action);
  void live_panel(TrainerSession& session, double frame_ms, const render::RenderSnapshot* snap);
  void result_panel(TrainerSession& session);
  void history_panel();
  void view_panel(render::Renderer& renderer, render::Microscope& microscope);
  void refresh_levels();

  TrainerOptions options_;
  TrainerConfig config_;
  int drill_index_ = 1;
  std::vector<std::string> levels_;
  int level_index_ = 0;
  int device_index_[2] = {0, 0};
  char trainee_[64] = {};
  char report_path_[256] = "phaco-report.html";
  std::string message_;
  struct Shown {
    double t_s;
    std::string text;
    bool warning;
  };
  std::deque<Shown> events_;
  std::vector<TrainerEvent> polled_;
  nlohmann::json report_;  // the last finished drill's
  bool finished_ = false;
  nlohmann::json history_ = nlohmann::json::array();
  BackgroundSync* sync_ = nullptr;
  std::set<std::string> intro_seen_;  // drills whose controls were shown on their first start
  bool controls_open_ = false;
  std::vector<report::TermText> rows_;  // the Result table, formatted once per finish
  std::vector<bool> row_fits_;          // each row's metric name shown whole (last frame)
  bool result_on_screen_ = true;        // the Result panel lies inside the window (last frame)
};

}  // namespace phaco::trainer
