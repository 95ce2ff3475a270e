// phaco-perf — the OpenPhaco performance harness.
//
// `phaco-perf foundation` measures what the engine foundation offers: eye-mesh generation time and
// element counts per resolution level, and the frame cost of the empty scene (tools moving, no
// physics) at 1 and 2 threads; it writes perf/results/*.csv and regenerates perf/RESULTS.md.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "engine/core/clock.hpp"
#include "engine/core/error.hpp"
#include "engine/io/scenario.hpp"
#include "perf/machine.hpp"
#include "procedures/eye/eye_mesh.hpp"
#include "procedures/scene/run.hpp"

namespace {

namespace fs = std::filesystem;
using namespace phaco;

constexpr const char* kUsage = R"(phaco-perf — OpenPhaco performance harness

usage:
  phaco-perf foundation [--max-level L] [--scenario FILE] [--frames-repeat N] [--out-dir DIR]
      Mesh generation time and element counts for levels 0..L (default 7), and the frame cost of
      the empty scene (default data/scenarios/empty_scene.json) at 1 and 2 threads, best of N runs
      (default 3). Writes DIR/results/foundation_levels.csv, DIR/results/empty_scene.csv and
      regenerates DIR/RESULTS.md (DIR defaults to the source tree's perf/).
  phaco-perf --help
)";

struct LevelRow {
  int level = 0;
  size_t capsule_vertices = 0, capsule_triangles = 0, capsule_iso_vertices = 0, cornea_vertices = 0,
         iris_vertices = 0, globe_vertices = 0, lens_surface_vertices = 0, lens_vertices = 0, lens_tets = 0;
  double surfaces_s = 0, tets_s = 0;
};

struct SceneRow {
  int threads = 0;
  uint64_t frames = 0;
  double frame_p50_ms = 0, frame_p99_ms = 0, mean_ms = 0;
  std::string hash;
};

void progress(const std::string& what, int done, int total) {
  const int width = 30;
  const int filled = total > 0 ? done * width / total : width;
  std::fprintf(stderr, "\r[%s%s] %d/%d %-40s", std::string(filled, '#').c_str(),
               std::string(width - filled, '.').c_str(), done, total, what.c_str());
  if (done == total) std::fputc('\n', stderr);
  std::fflush(stderr);
}

LevelRow measure_level(int level) {
  const eye::EyeParams params = eye::default_eye_params();
  const eye::Resolution res = eye::resolution_for_level(level);
  LevelRow row;
  row.level = level;
  Stopwatch clock;
  const SurfaceMesh capsule = eye::make_capsule(params, res, eye::CapsuleLayout::Curvilinear);
  const SurfaceMesh cornea = eye::make_cornea(params, res);
  const SurfaceMesh iris = eye::make_iris(params, res);
  const SurfaceMesh globe = eye::make_globe(params, res);
  const SurfaceMesh lens_surface = eye::make_lens_surface(params, res);
  row.surfaces_s = clock.elapsed_s();
  row.capsule_iso_vertices = eye::make_capsule(params, res, eye::CapsuleLayout::Isotropic).vertices.size();
  clock.restart();
  const TetMesh lens = eye::make_lens_tets(params, res);
  row.tets_s = clock.elapsed_s();
  row.capsule_vertices = capsule.vertices.size();
  row.capsule_triangles = capsule.triangles.size();
  row.cornea_vertices = cornea.vertices.size();
  row.iris_vertices = iris.vertices.size();
  row.globe_vertices = globe.vertices.size();
  row.lens_surface_vertices = lens_surface.vertices.size();
  row.lens_vertices = lens.vertices.size();
  row.lens_tets = lens.tets.size();
  return row;
}

SceneRow measure_scene(const Scenario& scenario, int threads, int repeats, const fs::path& cache) {
  SceneRow best;
  for (int r = 0; r < repeats; ++r) {
    SceneOptions o;
    o.threads = threads;
    o.cache_dir = cache;
    const RunReport report = run_scenario(scenario, o);
    if (r == 0 || report.frame.p50_ms < best.frame_p50_ms) {
      best = {threads, report.frames, report.frame.p50_ms, report.frame.p99_ms, report.frame.mean_ms,
              report.state_hash};
    }
  }
  return best;
}

std::string fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

int foundation(const std::vector<std::string>& args) {
  int max_level = eye::kMaxLevel, repeats = 3;
  fs::path out_dir = fs::path(PHACO_SOURCE_DIR) / "perf";
  fs::path scenario_file = fs::path(PHACO_SOURCE_DIR) / "data/scenarios/empty_scene.json";
  for (size_t i = 0; i < args.size(); ++i) {
    auto value = [&]() -> std::string {
      if (i + 1 >= args.size()) throw InputError("foundation: " + args[i] + " needs a value");
      return args[++i];
    };
    if (args[i] == "--max-level") {
      max_level = std::stoi(value());
      if (max_level < eye::kMinLevel || max_level > eye::kMaxLevel) throw InputError("foundation: --max-level out of 0..7");
    } else if (args[i] == "--frames-repeat") {
      repeats = std::max(1, std::stoi(value()));
    } else if (args[i] == "--out-dir") {
      out_dir = value();
    } else if (args[i] == "--scenario") {
      scenario_file = value();
    } else {
      throw InputError("foundation: unknown option '" + args[i] + "'");
    }
  }
  const Scenario scenario = load_scenario(scenario_file);
  fs::create_directories(out_dir / "results");
  const fs::path cache = out_dir / "results" / ".mesh-cache";

  const int total = (max_level + 1) + 2;
  int done = 0;
  std::vector<LevelRow> levels;
  for (int level = 0; level <= max_level; ++level) {
    progress("mesh level " + std::to_string(level), done, total);
    levels.push_back(measure_level(level));
    ++done;
  }
  std::vector<SceneRow> scenes;
  for (int threads : {1, 2}) {
    progress("empty scene, " + std::to_string(threads) + " thread(s)", done, total);
    scenes.push_back(measure_scene(scenario, threads, repeats, cache));
    ++done;
  }
  progress("done", total, total);

  std::ofstream csv(out_dir / "results" / "foundation_levels.csv");
  csv << "level,capsule_vertices,capsule_triangles,capsule_isotropic_vertices,cornea_vertices,iris_vertices,"
         "globe_vertices,lens_surface_vertices,lens_vertices,lens_tets,surfaces_s,tets_s\n";
  for (const auto& r : levels) {
    csv << r.level << ',' << r.capsule_vertices << ',' << r.capsule_triangles << ',' << r.capsule_iso_vertices << ','
        << r.cornea_vertices << ',' << r.iris_vertices << ',' << r.globe_vertices << ',' << r.lens_surface_vertices
        << ',' << r.lens_vertices << ',' << r.lens_tets << ',' << r.surfaces_s << ',' << r.tets_s << '\n';
  }
  std::ofstream scsv(out_dir / "results" / "empty_scene.csv");
  scsv << "threads,frames,frame_p50_ms,frame_p99_ms,frame_mean_ms,state_hash\n";
  for (const auto& s : scenes) {
    scsv << s.threads << ',' << s.frames << ',' << s.frame_p50_ms << ',' << s.frame_p99_ms << ',' << s.mean_ms << ','
         << s.hash << '\n';
  }

  std::string md;
  md += "# OpenPhaco — performance results\n\n";
  md += "Regenerated by `phaco-perf foundation` (see perf/README.md); do not edit by hand. Each figure below was "
        "measured by that command on the machine described here.\n\n";
  md += "## Machine\n\n" + perf::machine_markdown(perf::describe_machine()) + "\n";
  md += "## Eye meshes per resolution level\n\n";
  md += "Standard eye (data/eye/standard_eye.json). Capsule: curvilinear rings-and-spokes layout (isotropic variant "
        "count beside it). Lens tets by TetGen with quality bounds. Generation is single-threaded; meshes are cached "
        "on disk after the first build, so a scene loads them in a fraction of these times.\n\n";
  md += "| level | capsule vertices | capsule triangles | isotropic capsule vertices | cornea vertices | iris vertices | "
        "globe vertices | lens surface vertices | lens vertices | lens tets | surfaces (s) | tets (s) |\n";
  md += "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const auto& r : levels) {
    md += "| " + std::to_string(r.level) + " | " + std::to_string(r.capsule_vertices) + " | " +
          std::to_string(r.capsule_triangles) + " | " + std::to_string(r.capsule_iso_vertices) + " | " +
          std::to_string(r.cornea_vertices) + " | " + std::to_string(r.iris_vertices) + " | " +
          std::to_string(r.globe_vertices) + " | " + std::to_string(r.lens_surface_vertices) + " | " +
          std::to_string(r.lens_vertices) + " | " + std::to_string(r.lens_tets) + " | " + fmt("%.3f", r.surfaces_s) +
          " | " + fmt("%.2f", r.tets_s) + " |\n";
  }
  md += "\n## Frame cost of the empty scene\n\n";
  md += "`" + fs::relative(scenario_file, PHACO_SOURCE_DIR).string() + "`: drill `" +
        std::string(to_string(scenario.drill)) + "`, level " + std::to_string(scenario.eye.level) +
        ", the bodies loaded but no physics systems yet (tools follow their tracks; the topology sync point applies "
        "an empty command queue). This is the scheduler's own overhead per frame: the floor under every later "
        "figure. Best p50 of " + std::to_string(repeats) + " runs.\n\n";
  md += "| threads | frames | frame p50 (µs) | frame p99 (µs) | frame mean (µs) | state hash |\n";
  md += "|---:|---:|---:|---:|---:|---|\n";
  for (const auto& s : scenes) {
    md += "| " + std::to_string(s.threads) + " | " + std::to_string(s.frames) + " | " + fmt("%.2f", 1e3 * s.frame_p50_ms) +
          " | " + fmt("%.2f", 1e3 * s.frame_p99_ms) + " | " + fmt("%.2f", 1e3 * s.mean_ms) + " | `" + s.hash + "` |\n";
  }
  const bool same = scenes.size() == 2 && scenes[0].hash == scenes[1].hash;
  md += same ? "\nThe state hash is equal for 1 and 2 threads: the run is bit-identical whatever the thread count.\n"
             : "\n**The state hashes differ between 1 and 2 threads: determinism is broken.**\n";
  std::ofstream(out_dir / "RESULTS.md") << md;
  std::printf("wrote %s\n", (out_dir / "RESULTS.md").c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  try {
    if (args.empty() || args[0] == "--help" || args[0] == "-h") {
      std::fputs(kUsage, args.empty() ? stderr : stdout);
      return args.empty() ? 2 : 0;
    }
    const std::string cmd = args[0];
    args.erase(args.begin());
    if (cmd == "foundation") return foundation(args);
    std::fprintf(stderr, "phaco-perf: unknown command '%s' (try --help)\n", cmd.c_str());
    return 2;
  } catch (const InputError& e) {
    std::fprintf(stderr, "phaco-perf: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "phaco-perf: internal error: %s\n", e.what());
    return 1;
  }
}
