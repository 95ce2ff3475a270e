#pragma once
// phaco-trainer --procedure FILE (issue 20 item 1, docs/procedures.md): the procedure's steps one
// after the other, each a TrainerSession on the eye the steps before it left (the incision's port,
// the torn rhexis, the sculpted trench), each scored as its drill, with the total in a
// "Procedure" panel and on stdout. With --procedure-out DIR, each step's recording, a procedure
// file over them (`phaco run DIR/procedure.json` replays it) and the procedure's report go there.
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "apps/trainer/trainer_options.hpp"
#include "procedures/procedure/procedure_run.hpp"
#include "procedures/trainer/trainer_session.hpp"

namespace phaco::trainer {

class ProcedureDriver {
 public:
  // scripted: every hand plays a script (close_when_done).
  ProcedureDriver(const std::filesystem::path& file, std::optional<std::filesystem::path> out_dir,
                  bool scripted);
  ProcedureDriver(const ProcedureDriver&) = delete;  // the sessions' hooks point here
  ProcedureDriver& operator=(const ProcedureDriver&) = delete;

  // The current step's configuration: `base`'s devices, trainee, threads and cache with the
  // step's scenario, the carried eye and the hook that takes the eye at the live run's end.
  TrainerConfig step_config(const TrainerConfig& base);
  // Once per UI frame: when the step's session is over (it ended, or the Result panel finished
  // it), scores the step and carries the eye on; true when the next step is to start.
  bool step_over(TrainerSession& session);
  bool done() const { return procedure_done(state_); }
  // Done, and every hand played a script (scripted, track, replay): the trainer closes, as an
  // unattended run does; a trainee's window stays open on the Procedure panel.
  bool close_when_done() const { return done() && scripted_; }
  void draw_panel() const;  // between ImGui::NewFrame and ImGui::Render

 private:
  void write_out() const;

  Procedure procedure_;
  ProcedureState state_;  // written by the UI thread only, under mutex_
  std::optional<std::filesystem::path> out_dir_;
  mutable std::mutex mutex_;
  std::optional<ProcedureState> pending_;  // the last live run's end (simulation thread)
  const TrainerSession* taken_ = nullptr;  // the session whose end was taken
  std::vector<Scenario> recordings_;       // the steps as the trainee did them
  bool scripted_ = false;                  // every hand plays a script
};

// --procedure's driver, with `config` set to its first step; null without --procedure.
std::unique_ptr<ProcedureDriver> start_procedure(const TrainerOptions& o, TrainerConfig& config);

}  // namespace phaco::trainer
