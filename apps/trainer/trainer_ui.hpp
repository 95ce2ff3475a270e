#pragma once
// phaco-trainer's panels (Dear ImGui; issue 8 item 2): choose trainee, drill, difficulty and
// devices; start, pause, restart, finish, replay the last run; live status and warnings as they
// happen (run-out, radial tear-out, capsule breach, corneal stress, port stress); the score and
// its terms at the end, written as the HTML report on request; the trainee's past sessions from
// the records database; the microscope's zoom and focus, guidance and stereo.
#include <deque>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "apps/trainer/trainer_options.hpp"
#include "engine/render/renderer.hpp"
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
  // render frame's duration.
  UiAction draw(TrainerSession& session, render::Renderer& renderer, render::Microscope& microscope,
                double frame_ms);
  // The configuration the user chose (after Restart).
  const TrainerConfig& config() const { return config_; }
  // The background upload to a centre (--sync-to), asked after each stored drill; may be null.
  void set_sync(BackgroundSync* sync) { sync_ = sync; }

 private:
  void finish(TrainerSession& session);  // the drill's report (and record), once
  void drill_panel(TrainerSession& session, UiAction& action);
  void live_panel(TrainerSession& session, double frame_ms);
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
};

}  // namespace phaco::trainer
