#include "apps/phaco/commands.hpp"

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <optional>

#include "apps/phaco/args.hpp"
#include "apps/phaco/haptic_record.hpp"
#include "apps/phaco/procedure_command.hpp"
#include "apps/phaco/records_commands.hpp"
#include "engine/core/clock.hpp"
#include "engine/core/error.hpp"
#include "engine/core/utc_time.hpp"
#include "engine/haptics/device_factory.hpp"
#include "engine/io/scenario.hpp"
#include "engine/records/record_location.hpp"
#include "procedures/eye/eye_mesh.hpp"
#include "procedures/eye/mesh_cache.hpp"
#include "procedures/haptics/realtime_run.hpp"
#include "procedures/procedure/procedure_file.hpp"
#include "procedures/scene/run.hpp"
#include "procedures/scene/scene_inputs.hpp"

namespace phaco::cli {

namespace {

int parse_int(const std::string& command, const std::string& option, const std::string& text,
              int lo, int hi) {
  int value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc{} || end != text.data() + text.size() || value < lo || value > hi) {
    throw InputError(command + ": " + option + " expects an integer in " + std::to_string(lo) +
                     ".." + std::to_string(hi) + ", got '" + text + "'");
  }
  return value;
}

double parse_seconds(const std::string& command, const std::string& option, const std::string& text,
                     double lo, double hi) {
  double value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc{} || end != text.data() + text.size() || !(value >= lo && value <= hi)) {
    throw InputError(command + ": " + option + " expects a number in " + std::to_string(lo) + ".." +
                     std::to_string(hi) + ", got '" + text + "'");
  }
  return value;
}

SceneOptions scene_options(const Args& a, const std::string& command) {
  SceneOptions o;
  if (auto t = a.option("--threads")) o.threads = parse_int(command, "--threads", *t, 1, 256);
  if (auto c = a.option("--cache-dir")) o.cache_dir = *c;
  return o;
}

}  // namespace

void print_run(const Args& a, const nlohmann::json& report, const std::string& summary) {
  if (a.flag("--json")) {
    std::printf("%s\n", report.dump(2).c_str());
  } else {
    std::fputs(summary.c_str(), stdout);
    if (auto path = a.option("--report")) std::printf("report written to %s\n", path->c_str());
  }
}

int validate(const std::vector<std::string>& raw) {
  const Args a = parse_args("validate", raw, {}, {});
  if (a.positional.empty()) throw InputError("validate: give one or more scenario files");
  int status = kOk;
  for (const auto& file : a.positional) {
    try {
      if (is_procedure_file(file)) {
        validate_procedure_file(file);
        continue;
      }
      const Scenario s = load_scenario(file);
      // The drill file, the difficulty and the eye parameters, as `run` reads them before meshes.
      check_scene_inputs(s);
      std::printf("%s: ok (%s, %zu hand(s), %.3f s, %llu frames)\n", file.c_str(),
                  std::string(to_string(s.drill)).c_str(), s.hands.size(), s.duration_s,
                  static_cast<unsigned long long>(s.frame_count()));
    } catch (const InputError& e) {
      std::fprintf(stderr, "%s\n", e.what());
      status = kBadInput;
    }
  }
  return status;
}

int mesh(const std::vector<std::string>& raw) {
  const Args a =
      parse_args("mesh", raw, {"--level", "--out", "--layout", "--params"}, {"--no-tets"});
  if (!a.positional.empty())
    throw InputError("mesh: unexpected argument '" + a.positional[0] + "'");
  const auto out = a.option("--out");
  if (!out) throw InputError("mesh: --out DIR is required");
  const int level = parse_int("mesh", "--level", a.option("--level").value_or("3"), eye::kMinLevel,
                              eye::kMaxLevel);
  const std::string layout_name = a.option("--layout").value_or("curvilinear");
  if (layout_name != "curvilinear" && layout_name != "isotropic") {
    throw InputError("mesh: --layout expects 'curvilinear' or 'isotropic', got '" + layout_name +
                     "'");
  }
  const auto layout =
      layout_name == "isotropic" ? eye::CapsuleLayout::Isotropic : eye::CapsuleLayout::Curvilinear;
  const eye::EyeParams params = a.option("--params") ? eye::load_eye_params(*a.option("--params"))
                                                     : eye::default_eye_params();
  const eye::Resolution res = eye::resolution_for_level(level);

  eye::EyeMeshes m;
  m.res = res;
  Stopwatch clock;
  m.cornea = eye::make_cornea(params, res);
  m.capsule = eye::make_capsule(params, res, layout);
  m.iris = eye::make_iris(params, res);
  m.globe = eye::make_globe(params, res);
  m.lens_surface = eye::make_lens_surface(params, res);
  const double surfaces_s = clock.elapsed_s();
  double tets_s = 0;
  if (!a.flag("--no-tets")) {
    clock.restart();
    m.lens_tets = eye::make_lens_tets(params, res);
    tets_s = clock.elapsed_s();
  }
  std::error_code ec;
  std::filesystem::create_directories(*out, ec);
  if (ec) throw InputError("mesh: cannot create '" + *out + "': " + ec.message());
  eye::write_eye_meshes(m, *out);

  std::printf("level %d (%s capsule) -> %s\n", level, layout_name.c_str(), out->c_str());
  auto row = [](const char* name, const SurfaceMesh& s) {
    std::printf("  %-13s %8zu vertices %8zu triangles\n", name, s.vertices.size(),
                s.triangles.size());
  };
  row("cornea", m.cornea);
  row("capsule", m.capsule);
  row("iris", m.iris);
  row("globe", m.globe);
  row("lens_surface", m.lens_surface);
  if (m.lens_tets) {
    std::printf("  %-13s %8zu vertices %8zu tets\n", "lens", m.lens_tets->vertices.size(),
                m.lens_tets->tets.size());
  }
  std::printf("generated surfaces in %.3f s, tets in %.3f s\n", surfaces_s, tets_s);
  return kOk;
}

// `run --haptics SPEC`: the scene in real time with the 1 kHz haptic thread, a device in one hand.
int run_with_haptics(const Args& a, const Scenario& scenario, const std::string& spec_text) {
  const DeviceSpec spec = parse_device_spec(spec_text);
  Hand hand = spec.hand.value_or(Hand::Right);
  if (auto h = a.option("--hand")) {
    const auto parsed = parse_hand(*h);
    if (!parsed) throw InputError("run: --hand expects 'left' or 'right', got '" + *h + "'");
    hand = *parsed;
  }
  DeviceContext context;
  context.scenario = &scenario;
  context.hand = hand;
  HapticSessionConfig config;
  config.loop.realtime = !a.flag("--no-rt");
  config.loop.lock_memory = config.loop.realtime;
  if (auto spin = a.option("--spin-us")) {
    config.loop.spin_ns =
        static_cast<int64_t>(parse_seconds("run", "--spin-us", *spin, 0, 1000) * 1e3);
  }
  if (auto most = a.option("--max-spin-us")) {
    config.loop.max_spin_ns =
        static_cast<int64_t>(parse_seconds("run", "--max-spin-us", *most, 0, 1000) * 1e3);
  }
  HapticSession session(config);
  // --record: the device's samples become the stored recording (apps/phaco/haptic_record.hpp).
  const auto recording = HapticRecording::from_args(a, scenario, hand, spec_text);
  auto device = make_device(spec, context);
  session.attach(hand, recording ? recording->wrap(std::move(device)) : std::move(device));
  RealtimeRunOptions run;
  if (auto d = a.option("--duration"))
    run.duration_s = parse_seconds("run", "--duration", *d, 0.01, 86400);
  if (auto t = a.option("--stall-at"))
    run.stall_at_s = parse_seconds("run", "--stall-at", *t, 0, 86400);
  if (auto m = a.option("--stall-ms"))
    run.stall_ms = parse_seconds("run", "--stall-ms", *m, 0, 60000);
  const RealtimeRunReport report = run_realtime(scenario, scene_options(a, "run"), session, run);
  nlohmann::json j = to_json(report);
  j["scenario"] = scenario.source;
  j["device"] = spec_text;
  j["hand"] = std::string(to_string(hand));
  if (auto path = a.option("--report")) write_text(*path, j.dump(2) + "\n");
  if (recording) {
    recording->store(scenario, scene_options(a, "run"), j,
                     run.duration_s > 0 ? run.duration_s : scenario.duration_s);
  }
  if (a.flag("--json")) {
    std::printf("%s\n", j.dump(2).c_str());
  } else {
    std::printf("%s, %s hand on device '%s'\n", scenario.source.c_str(),
                std::string(to_string(hand)).c_str(), spec_text.c_str());
    std::fputs(summary_text(report).c_str(), stdout);
    if (auto path = a.option("--report")) std::printf("report written to %s\n", path->c_str());
  }
  return kOk;
}

std::optional<std::filesystem::path> record_target(const Args& a) {
  const auto trainee = a.option("--trainee");
  if (!a.option("--record") && !trainee) return std::nullopt;
  if (!trainee) throw InputError("run: --record needs --trainee NAME");
  const std::filesystem::path db =
      a.option("--record") ? std::filesystem::path(*a.option("--record")) : default_records_db();
  check_record_target(db, *trainee);
  return db;
}

int run(const std::vector<std::string>& raw) {
  const Args a = parse_args(
      "run", raw,
      {"--threads", "--report", "--cache-dir", "--haptics", "--hand", "--duration", "--stall-at",
       "--stall-ms", "--spin-us", "--max-spin-us", "--record", "--trainee", "--difficulty"},
      {"--json", "--no-rt"});
  if (a.positional.size() != 1) throw InputError("run: give exactly one scenario file");
  if (is_procedure_file(a.positional[0]))
    return run_procedure_file(a, scene_options(a, "run"));  // docs/procedures.md
  Scenario scenario = load_scenario(a.positional[0]);
  // A level of the drill file (docs/drills.md); checked when the scene is built.
  if (auto level = a.option("--difficulty")) scenario.difficulty = *level;
  if (auto spec = a.option("--haptics")) return run_with_haptics(a, scenario, *spec);
  for (const char* o :
       {"--hand", "--duration", "--stall-at", "--stall-ms", "--spin-us", "--max-spin-us"}) {
    if (a.option(o)) throw InputError(std::string("run: ") + o + " needs --haptics");
  }
  if (a.flag("--no-rt")) throw InputError("run: --no-rt needs --haptics");
  // Records (issue 7, docs/records.md): checked before the drill, stored after it.
  const std::optional<std::filesystem::path> db = record_target(a);
  const auto trainee = a.option("--trainee");
  const RunReport report = run_scenario(scenario, scene_options(a, "run"));
  nlohmann::json j = to_json(report);
  j["date"] = utc_now();  // when the run finished, for the HTML report and the records
  if (auto path = a.option("--report")) write_text(*path, j.dump(2) + "\n");
  if (db) {
    const int64_t id = record_run(*db, *trainee, scenario, j);
    std::fprintf(stderr, "recorded as record %lld in %s\n", static_cast<long long>(id),
                 shown_location(db->string()).c_str());
  }
  print_run(a, j, summary_text(report));
  return kOk;
}

int graph(const std::vector<std::string>& raw) {
  const Args a = parse_args("graph", raw, {"--out", "--threads", "--cache-dir"}, {});
  if (a.positional.size() != 1) throw InputError("graph: give exactly one scenario file");
  const Scenario scenario = load_scenario(a.positional[0]);
  const auto scene = build_scene(scenario, scene_options(a, "graph"));
  const std::string dot = scene->graph->to_dot();
  if (auto path = a.option("--out")) {
    write_text(*path, dot);
  } else {
    std::fputs(dot.c_str(), stdout);
  }
  return kOk;
}

}  // namespace phaco::cli
