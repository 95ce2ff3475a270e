#include "apps/trainer/trainer_options.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>

#include "apps/phaco/args.hpp"
#include "engine/core/error.hpp"
#include "engine/io/json_reader.hpp"
#include "engine/records/record_location.hpp"
#include "engine/records/record_run.hpp"
#include "procedures/eye/eye_params.hpp"

namespace phaco::trainer {

const char* const kUsage = R"(phaco-trainer — OpenPhaco's cataract-surgery trainer (docs/trainer.md)

usage:
  phaco-trainer [--drill NAME | --scenario FILE] [--difficulty LEVEL] [--trainee NAME] [--db DB]
                [--sync-to URI]
                [--left DEVICE] [--right DEVICE] [--size WxH] [--stereo] [--no-guidance]
                [--duration S] [--threads N] [--cache-dir DIR]
  phaco-trainer ... --screenshot OUT.png [--after SECONDS] [--no-ui]
  phaco-trainer ... --stats OUT.json [--stats-after SECONDS] [--no-render]
  phaco-trainer ... --soak OUT.json [--soak-for SECONDS]
  phaco-trainer ... --ui-state OUT.json [--views DIR]
  phaco-trainer --procedure FILE [--procedure-out DIR] [--left DEVICE] [--right DEVICE] ...
  phaco-trainer --help | --version

  --drill       corneal_incision | capsulorhexis | phaco_sculpting | nucleus_removal (default
                capsulorhexis); the tools start where the drill's expert scenario starts them
  --scenario    any scenario file instead (its tracks give the tools and start poses)
  --procedure   the whole operation in one eye (docs/procedures.md): a procedure file, e.g.
                data/procedures/cataract_expert.json; its steps (incision, capsulorhexis,
                sculpting, nucleus removal) follow one another, the incision cut becomes the main
                port, the torn rhexis the opening, the trench the groove; each step is scored as
                its drill and the "Procedure" panel shows the step scores and the total;
                with every hand scripted (scripted, track, replay:) it closes when done
  --procedure-out  with --procedure: when it is done, write each step's recording, a procedure
                file over them (replay: phaco run DIR/procedure.json) and the report to DIR
  --difficulty  a level of the drill file (data/drills/<drill>.json: standard, easy, hard, ...)
  --left/--right  the hand's device: desktop (mouse, keyboard, gamepad; default), scripted (the
                scenario's track in real time through the 1 kHz loop), track (the scene plays the
                track), replay:FILE, udp:LOCALPORT@HOST:PORT, openhaptics[:NAME]
  --duration    simulated seconds before the drill ends (default: the scenario's when every hand
                plays a script, else 900)
  --trainee     store each finished drill in the records database (phaco history NAME)
  --db          the records database: this station's SQLite file (default
                $PHACO_DB, else $XDG_DATA_HOME/openphaco/records.sqlite, by default
                ~/.local/share/openphaco/records.sqlite) or a postgresql:// URI
  --sync-to     a training centre's PostgreSQL server (postgresql://USER@HOST/DB, or
                $PHACO_SYNC_TO): drills are stored on this station first, then uploaded in the
                background; while the centre is unreachable it retries every 30 s (docs/records.md)
  --screenshot  run unattended: save the view after --after simulated seconds (default 5), exit
  --stats       run unattended: after --stats-after wall seconds (default 20) write the render
                frame rate, the simulation rate and the haptic period as JSON, exit
  --no-render   with --stats: keep the window and the loop but draw nothing (the baseline)
  --soak        run unattended drill after drill (the three drills in turn from the one given,
                scripted hands unless --left/--right say otherwise) for --soak-for wall seconds
                (default 60), then write per-drill resident memory, live GL objects and the
                haptic period as JSON, exit (phaco-perf soak charts and checks it)
  --ui-state    while running, rewrite OUT.json ten times a second with what the trainee sees:
                the active hand, each tip's height readout, the Result table (for tests that
                drive the window with xdotool)
  --views       the folder F12 saves the view to (default: the current one): view-NNN.png, the
                view without the panels, and view-NNN.json, the tools' tips and shafts, the
                globe's turn and the microscope it shows

controls: mouse moves the selected hand's tip, only while the pointer is over the view (over a
panel or outside the window both tools stay put; hold the middle button or Shift to move the
pointer alone), wheel = depth (0.1 mm a click), left button = grip / ultrasound, right button =
aspiration; Tab switches hands; a gamepad drives both hands (sticks, triggers = grip/pedal,
bumpers = deeper); Space pauses; R restarts; G toggles the guidance cues; F1 shows the controls;
F12 saves the view (--views); Esc quits. The label by each tip is its height above the tissue
under it.
An interactive run remembers the trainee, devices, drill and level it ended with in
$XDG_CONFIG_HOME/openphaco/trainer.json (default ~/.config/openphaco) and starts with them when the
command line does not say otherwise.
Data (eye, drills, scenarios): $PHACO_DATA_DIR, else ../share/openphaco beside the program
(docs/install.md); --version prints the version, the source revision and the data folder in use.
Exit codes: 0 done, 2 bad input (named), 3 no display or OpenGL 3.3, or an unattended run timed out.
)";

namespace {

double number(const std::string& option, const std::string& text, double lo, double hi) {
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0' || errno != 0 || !std::isfinite(v) || v < lo || v > hi) {
    throw InputError(option + ": expected a number in [" + io::format_number(lo) + ", " +
                     io::format_number(hi) + "], got '" + text + "'");
  }
  return v;
}

}  // namespace

std::filesystem::path drill_scenario(const std::string& drill) {
  const std::string name = drill == "incision"    ? "corneal_incision"
                           : drill == "rhexis"    ? "capsulorhexis"
                           : drill == "sculpting" ? "phaco_sculpting"
                           : drill == "nucleus"   ? "nucleus_removal"
                                                  : drill;
  if (name != "corneal_incision" && name != "capsulorhexis" && name != "phaco_sculpting" &&
      name != "nucleus_removal") {
    throw InputError("--drill: unknown drill '" + drill +
                     "'; expected corneal_incision, capsulorhexis, phaco_sculpting or "
                     "nucleus_removal");
  }
  return eye::data_dir() / "scenarios" / (name + "_expert.json");
}

TrainerOptions parse_options(const std::vector<std::string>& raw) {
  const cli::Args a = cli::parse_args(
      "command line", raw, {"--drill",     "--scenario",      "--difficulty",  "--left",
                            "--right",     "--trainee",       "--db",          "--sync-to",
                            "--size",      "--threads",       "--cache-dir",   "--screenshot",
                            "--after",     "--stats",         "--stats-after", "--duration",
                            "--timeout",   "--soak",          "--soak-for",    "--ui-state",
                            "--procedure", "--procedure-out", "--views"},
      {"--stereo", "--no-guidance", "--no-ui", "--no-render"}, "phaco-trainer --help");
  if (!a.positional.empty()) {
    throw InputError("unexpected argument '" + a.positional[0] +
                     "' (give a scenario with --scenario)");
  }
  TrainerOptions o;
  if (a.option("--drill") && a.option("--scenario")) {
    throw InputError("give --drill or --scenario, not both");
  }
  o.scenario = a.option("--scenario")
                   ? std::filesystem::path(*a.option("--scenario"))
                   : drill_scenario(a.option("--drill").value_or("capsulorhexis"));
  if (auto v = a.option("--difficulty")) o.difficulty = *v;
  if (auto v = a.option("--left")) o.left = *v;
  if (auto v = a.option("--right")) o.right = *v;
  if (auto v = a.option("--trainee")) o.trainee = *v;
  if (auto v = a.option("--db")) o.db = *v;
  if (auto v = a.option("--sync-to")) {
    o.sync_to = *v;
  } else if (const char* env = std::getenv("PHACO_SYNC_TO"); env && *env) {
    o.sync_to = env;
  }
  if (!o.sync_to.empty() && !is_postgres_uri(o.sync_to))
    throw InputError("--sync-to: expected a postgresql:// URI, got '" + shown_location(o.sync_to) +
                     "'");
  // The station records to its own file first: --db (or $PHACO_DB) must not be a server too.
  if (!o.sync_to.empty() && is_postgres_uri((o.db.empty() ? default_records_db() : o.db).string()))
    throw InputError("--sync-to: the station records to its own file first; --db is a server");
  if (auto v = a.option("--size")) {
    const auto x = v->find('x');
    if (x == std::string::npos)
      throw InputError("--size: expected WxH, e.g. 1280x720, got '" + *v + "'");
    o.width = static_cast<int>(number("--size", v->substr(0, x), 64, 8192));
    o.height = static_cast<int>(number("--size", v->substr(x + 1), 64, 8192));
  }
  if (auto v = a.option("--threads")) o.threads = static_cast<int>(number("--threads", *v, 1, 64));
  if (auto v = a.option("--cache-dir")) o.cache_dir = *v;
  if (auto v = a.option("--duration")) o.duration_s = number("--duration", *v, 1, 86400);
  if (auto v = a.option("--screenshot")) o.screenshot = *v;
  if (auto v = a.option("--after")) o.after_s = number("--after", *v, 0, 3600);
  if (auto v = a.option("--stats")) o.stats = *v;
  if (auto v = a.option("--ui-state")) o.ui_state = *v;
  if (auto v = a.option("--views")) {
    if (!std::filesystem::is_directory(*v))
      throw InputError("--views: '" + *v + "' is not a folder (F12 saves the view there)");
    o.views_dir = *v;
  }
  if (auto v = a.option("--stats-after")) o.stats_after_s = number("--stats-after", *v, 0.5, 3600);
  if (auto v = a.option("--timeout")) o.timeout_s = number("--timeout", *v, 1, 86400);
  o.stereo = a.flag("--stereo");
  o.guidance = !a.flag("--no-guidance");
  o.ui = !a.flag("--no-ui") && !o.screenshot;  // a screenshot shows the view alone
  o.render = !a.flag("--no-render");
  if (!o.render && !o.stats) throw InputError("--no-render: only with --stats (the baseline)");
  if (o.screenshot && o.stats) throw InputError("--screenshot or --stats, not both");
  if (o.ui_state && !o.ui)
    throw InputError("--ui-state: not with --no-ui or --screenshot (it reports the panels)");
  if (a.option("--after") && !o.screenshot) throw InputError("--after: only with --screenshot");
  if (a.option("--stats-after") && !o.stats) throw InputError("--stats-after: only with --stats");
  if (auto v = a.option("--soak")) {
    if (o.screenshot || o.stats) throw InputError("--soak: not with --screenshot or --stats");
    o.soak = *v;
    if (!a.option("--left")) o.left = "scripted";
    if (!a.option("--right")) o.right = "scripted";
  }
  if (auto v = a.option("--soak-for")) {
    if (!o.soak) throw InputError("--soak-for: only with --soak");
    o.soak_for_s = number("--soak-for", *v, 5, 86400);
  }
  if (auto v = a.option("--procedure")) {
    if (a.option("--drill") || a.option("--scenario") || o.soak)
      throw InputError("--procedure: not with --drill, --scenario or --soak (its steps say)");
    o.procedure = *v;
  }
  if (auto v = a.option("--procedure-out")) {
    if (!o.procedure) throw InputError("--procedure-out: only with --procedure");
    o.procedure_out = *v;
  }
  // A soak gives up only well after its own length (the drill in progress ends first).
  if (o.soak && !a.option("--timeout")) o.timeout_s = o.soak_for_s + 600;
  return o;
}

}  // namespace phaco::trainer
