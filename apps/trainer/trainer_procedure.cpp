#include "apps/trainer/trainer_procedure.hpp"

#include <imgui.h>

#include <cstdio>
#include <fstream>

#include "engine/core/error.hpp"

namespace phaco::trainer {

namespace {

void write_json(const std::filesystem::path& file, const nlohmann::json& j) {
  std::ofstream out(file);
  if (!out || !(out << j.dump(2) << "\n").flush())
    throw InputError("--procedure-out: cannot write " + file.string());
}

}  // namespace

ProcedureDriver::ProcedureDriver(const std::filesystem::path& file,
                                 std::optional<std::filesystem::path> out_dir, bool scripted)
    : procedure_(load_procedure(file)), out_dir_(std::move(out_dir)), scripted_(scripted) {
  state_ = begin_procedure(procedure_);
}

TrainerConfig ProcedureDriver::step_config(const TrainerConfig& base) {
  TrainerConfig c = base;
  c.scenario = procedure_.steps.at(state_.next);
  c.scene.carried = &state_.carried;
  // The simulation thread, at the live run's end: score the step and carry its eye on a copy;
  // step_over takes it once the session is over (a restarted run's end is replaced by the next).
  c.at_end = [this, drill = c.scenario.drill](Scene& scene) {
    if (scene.scenario.drill != drill) return;  // another drill chosen in the Drill panel
    std::unique_lock lock(mutex_);
    ProcedureState next = state_;
    lock.unlock();
    finish_step(next, scene, 0.0);
    lock.lock();
    pending_ = std::move(next);
  };
  return c;
}

bool ProcedureDriver::step_over(TrainerSession& session) {
  if (done() || taken_ == &session) return false;
  const TrainerState st = session.state();
  if (st == TrainerState::Ended) {
    session.finish();
  } else if (st != TrainerState::Idle || !session.last_recording()) {
    return false;
  }
  taken_ = &session;
  {
    std::lock_guard lock(mutex_);
    if (!pending_) return false;  // not the step's drill (the Drill panel started another)
    state_ = std::move(*pending_);
    pending_.reset();
    // The step took the live run's wall time, pauses left out.
    const double wall =
        session.last_report().value("live", nlohmann::json::object()).value("wall_s", 0.0);
    state_.report.steps.back().run.wall_time_s = wall;
    state_.report.wall_time_s += wall;
  }
  recordings_.push_back(*session.last_recording());
  const RunReport& r = state_.report.steps.back().run;
  std::printf("procedure: step %zu %s scored %.1f\n", state_.report.steps.size(), r.drill.c_str(),
              r.metrics.value("score", 0.0));
  if (done()) {
    std::printf("procedure: total %.1f / 100%s%s\n", state_.report.total,
                state_.report.failed ? "  FAILED at " : "", state_.report.failure.c_str());
    if (out_dir_) write_out();
  }
  std::fflush(stdout);
  return !done();
}

void ProcedureDriver::write_out() const {
  std::filesystem::create_directories(*out_dir_);
  nlohmann::json steps = nlohmann::json::array();
  for (size_t i = 0; i < recordings_.size(); ++i) {
    const std::string name =
        std::to_string(i + 1) + "_" + std::string(to_string(recordings_[i].drill)) + ".json";
    write_json(*out_dir_ / name, to_json(recordings_[i]));
    steps.push_back({{"scenario", name}});
  }
  write_json(*out_dir_ / "procedure.json",
             {{"name", procedure_.name + " (recorded in the trainer)"},
              {"description", "Replay: phaco run procedure.json"},
              {"steps", steps}});
  write_json(*out_dir_ / "report.json", to_json(state_.report));
  std::printf("procedure: recorded in %s (replay: phaco run %s)\n", out_dir_->c_str(),
              (*out_dir_ / "procedure.json").c_str());
}

void ProcedureDriver::draw_panel() const {
  const ImVec2 display = ImGui::GetIO().DisplaySize;
  // Bottom centre, clear of the Drill, Live, Microscope and History panels.
  ImGui::SetNextWindowPos(ImVec2(0.5f * display.x, display.y - 10), ImGuiCond_Always,
                          ImVec2(0.5f, 1.0f));
  ImGui::Begin("Procedure", nullptr, ImGuiWindowFlags_AlwaysAutoResize);
  ImGui::TextUnformatted(procedure_.name.empty() ? procedure_.source.c_str()
                                                 : procedure_.name.c_str());
  std::lock_guard lock(mutex_);
  const ProcedureReport& r = state_.report;
  for (size_t i = 0; i < procedure_.steps.size(); ++i) {
    const std::string drill(to_string(procedure_.steps[i].drill));
    if (i < r.steps.size()) {
      ImGui::Text("%zu  %-18s %5.1f", i + 1, drill.c_str(),
                  r.steps[i].run.metrics.value("score", 0.0));
    } else if (!done() && i == state_.next) {
      ImGui::Text("%zu  %-18s  in progress", i + 1, drill.c_str());
    } else {
      ImGui::Text("%zu  %-18s  %s", i + 1, drill.c_str(), done() ? "not run (0)" : "-");
    }
  }
  if (done()) {
    ImGui::Separator();
    ImGui::Text("total %.1f / 100", r.total);
    if (r.failed) {
      ImGui::PushTextWrapPos(ImGui::GetFontSize() * 28.0f);  // a long reason wraps
      ImGui::TextColored(ImVec4(1.0f, 0.45f, 0.3f, 1.0f), "FAILED: %s", r.failure.c_str());
      ImGui::PopTextWrapPos();
    }
  }
  ImGui::End();
}

std::unique_ptr<ProcedureDriver> start_procedure(const TrainerOptions& o, TrainerConfig& config) {
  if (!o.procedure) return nullptr;
  const auto scripted = [](const std::string& d) {
    return d == "scripted" || d == "track" || d.rfind("replay:", 0) == 0;
  };
  auto driver = std::make_unique<ProcedureDriver>(*o.procedure, o.procedure_out,
                                                  scripted(o.left) && scripted(o.right));
  config = driver->step_config(config);
  return driver;
}

}  // namespace phaco::trainer
