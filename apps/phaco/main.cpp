// phaco — the headless OpenPhaco command: validate scenarios, generate eye meshes, run scenarios.
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "apps/phaco/cohort_command.hpp"
#include "apps/phaco/commands.hpp"
#include "apps/phaco/compare_command.hpp"
#include "apps/phaco/records_commands.hpp"
#include "apps/phaco/report_command.hpp"
#include "apps/phaco/sync_command.hpp"
#include "apps/phaco/version_text.hpp"
#include "engine/core/error.hpp"

namespace {

constexpr const char* kUsage = R"(phaco — OpenPhaco headless simulator

usage:
  phaco run FILE [--threads N] [--report OUT.json] [--json] [--cache-dir DIR]
                 [--record DB --trainee NAME] [--difficulty LEVEL]
      Run a scenario headless for its duration at its fixed step; print a summary with the
      drill's metrics and 0-100 score (docs/scoring.md), or, with --json, the JSON report; write
      the JSON report to OUT.json; with --trainee, store the run in the records database
      (DB, default $PHACO_DB, else $XDG_DATA_HOME/openphaco/records.sqlite, by default
      ~/.local/share/openphaco/records.sqlite; docs/records.md).
      Any DB may be an SQLite file or a postgresql:// URI (a training centre's server).
      --difficulty picks a level of the drill file (drills/<drill>.json in the data folder,
      e.g. standard, easy, hard; docs/drills.md) instead of the scenario's.
  phaco run PROCEDURE.json [--threads N] [--report OUT.json] [--json] [--difficulty LEVEL]
                           [--record DB --trainee NAME]
      A procedure (a file with "steps", e.g. procedures/cataract_expert.json in the data folder;
      docs/procedures.md): its drills one after the other in one eye (the incision cut is the
      main port, the torn rhexis the opening, the sculpted trench the groove), each scored as its
      drill, and the total; a complication fails the procedure there and says why. With
      --trainee, each step that ran is stored as its drill's record.
  phaco run FILE --haptics DEVICE [--hand left|right] [--no-rt] [--spin-us US] [--max-spin-us US]
                 [--duration S] [--stall-at S --stall-ms MS] [--threads N] [--report OUT.json] [--json]
                 [--record DB --trainee NAME]
      Run the scenario in real time with the 1 kHz haptic thread; DEVICE drives one hand's tool
      and feels the force of the local haptic model (docs/haptics.md):
        scripted[:left|right]            the scenario's own track for that hand, in real time
        replay:FILE[:left|right]         a recorded session (a scenario file)
        udp:LOCALPORT@PEERHOST:PEERPORT  a device driven by another process (docs/udp_bridge_protocol.md)
        openhaptics[:NAME]               a Phantom-class device (only when built with the SDK)
      The haptic thread asks for SCHED_FIFO (--no-rt: it does not) and the summary says whether
      it got it. The loop sleeps to a margin before each deadline, then spins; the margin follows
      the wake-up latency it observes, from --spin-us (default 60) up to --max-spin-us (default
      250; set it to --spin-us for a fixed margin).
      --duration runs longer or shorter than the scenario (it restarts when it ends);
      --stall-at/--stall-ms make the simulation hang once, to show the force stays continuous.
      --record stores the scenario with the track the device produced (docs/records.md).
  phaco validate FILE...
      Check scenario (and procedure) files and what they use (the drill file, its difficulty
      level, the eye parameters and overrides, each within its range; docs/scenario_format.md);
      every problem is named by file, JSON path and what was expected. A file validate accepts
      runs to its end.
  phaco mesh --level L --out DIR [--layout curvilinear|isotropic] [--no-tets] [--params FILE]
      Generate the standard eye's meshes at resolution level L (0..8, default eye level 3:
      about 8k capsule vertices, 50k lens tets) as OBJ and TetGen .node/.ele files.
  phaco report RUN.json --html OUT.html [--expert EXPERT.json]
      Write a run report (phaco run --report) as one self-contained HTML page: the score and its
      terms, every metric against its target, the events, and plots (force, speed, paths, the
      rhexis against its target circle, the trench from above) (docs/report.md); --expert adds
      the comparison with an expert's run report. A procedure's report: the total, the steps'
      table and each step's page.
  phaco compare RUN.json EXPERT.json [--json OUT.json]
      Compare a run report with an expert's: per hand, path distance, speed and force differences
      after dynamic time warping of the tool paths, the time ratio, and run - expert per metric
      (docs/compare.md). Two procedures' reports are compared step by step.
  phaco sync --to URI [--db FILE] [--all] [--batch N] [--json]
      Upload this station's records (its SQLite file, --db or the default) to a training
      centre's PostgreSQL server (URI postgresql://USER[:PASSWORD]@HOST[:PORT]/DB, or
      $PHACO_SYNC_TO; a password may also come from PGPASSFILE or PGPASSWORD and is never
      printed). Only what the centre has not acknowledged is sent (--all: everything again); the
      centre keeps each record once, so an interrupted or repeated sync loses and duplicates
      nothing (docs/records.md). Exit 3 when the centre refused some records.
  phaco cohort --html OUT.html [--db DB] [--title T] [--drill NAME]
      A training centre's cohort on one self-contained page: every trainee's learning curve per
      drill with the pass line, the pass rates, and each trainee's weakest metrics.
  phaco history TRAINEE [--db DB] [--json]
      The trainee's recorded sessions in date order (drill, score, key metrics) and the trend.
  phaco export ID [--db DB] [--xml OUT] [--json OUT] [--scenario OUT]
      One record as XML (seed 000 §6.4), JSON, or the scenario that replays it with phaco run.
  phaco export [ID] --xapi OUT.json [--db DB] [--trainee NAME] [--home-page IRI]
      Finished drills (one, the trainee's, or all) as xAPI 2.0 statements for a learning
      management system: score, success, duration and every metric with its unit; the
      statement id is the record's uuid (docs/records.md, "xAPI").
  phaco graph FILE [--out OUT.dot]
      Print the scenario's per-frame task graph as GraphViz DOT.
  phaco --help | --version

exit codes: 0 success, 2 bad input (message on stderr), 1 internal error.
  --version prints the version, the source revision and the data folder in use.

environment: PHACO_DATA_DIR (the data: eye/, drills/, scenarios/; default ../share/openphaco
  beside the executable, e.g. /usr/share/openphaco; docs/install.md), PHACO_CACHE_DIR (mesh
  cache, default $XDG_CACHE_HOME/openphaco/meshes or ~/.cache/openphaco/meshes), PHACO_DB.
)";

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty()) {
    std::fputs(kUsage, stderr);
    return phaco::cli::kBadInput;
  }
  const std::string command = args.front();
  args.erase(args.begin());
  try {
    if (command == "--help" || command == "-h" || command == "help") {
      std::fputs(kUsage, stdout);
      return phaco::cli::kOk;
    }
    if (command == "--version") {
      std::fputs(phaco::cli::version_text("phaco").c_str(), stdout);
      return phaco::cli::kOk;
    }
    for (const auto& a : args) {
      if (a == "--help" || a == "-h") {
        std::fputs(kUsage, stdout);
        return phaco::cli::kOk;
      }
    }
    if (command == "run") return phaco::cli::run(args);
    if (command == "validate") return phaco::cli::validate(args);
    if (command == "mesh") return phaco::cli::mesh(args);
    if (command == "graph") return phaco::cli::graph(args);
    if (command == "report") return phaco::cli::report(args);
    if (command == "compare") return phaco::cli::compare(args);
    if (command == "history") return phaco::cli::history(args);
    if (command == "export") return phaco::cli::export_record(args);
    if (command == "sync") return phaco::cli::sync(args);
    if (command == "cohort") return phaco::cli::cohort(args);
    std::fprintf(stderr, "phaco: unknown command '%s' (try 'phaco --help')\n", command.c_str());
    return phaco::cli::kBadInput;
  } catch (const phaco::InputError& e) {
    std::fprintf(stderr, "phaco: %s\n", e.what());
    return phaco::cli::kBadInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "phaco: internal error: %s\n", e.what());
    return phaco::cli::kInternalError;
  }
}
