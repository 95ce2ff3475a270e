// Issue 18 item 2: the scenario fuzzer. Mutations of the shipped scenarios (data/scenarios) and
// drill files (data/drills) go through what `phaco validate` and `phaco run` do, in process:
// load_scenario's parser and check_scene_inputs (validate), then build_scene, the fixed steps and
// report_of (run). Each mutation must either be refused as an InputError that names the file and a
// field ("FILE: json.path: ..."; `phaco` exits 2), or run to its end with every particle and tool
// finite and a complete report. Anything else (another exception, an InputError only the run finds)
// is a failure: the mutated file is kept and its path printed, to reproduce with `phaco run FILE`.
//
// Deterministic by seed: PHACO_FUZZ_SEED (default below) and PHACO_FUZZ_COUNT override; mutation
// i draws from its own generator (seed, i), so one failure reproduces alone. Each mutation is run
// at eye level 0 for at most 1 s simulated and kMaxFrames steps, so that the few thousand cases fit
// the CI budget (90 s in Release on two busy cores); most die in validation, which costs
// microseconds.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <numbers>
#include <numeric>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "components/particles.hpp"
#include "components/tool.hpp"
#include "engine/core/error.hpp"
#include "engine/io/bounds.hpp"
#include "engine/io/scenario.hpp"
#include "procedures/eye/eye_param_ranges.hpp"
#include "procedures/scene/run.hpp"
#include "procedures/scene/scene.hpp"
#include "procedures/scene/scene_inputs.hpp"
#include "tests/support/particle_checks.hpp"
#include "tests/support/sanitizers.hpp"

namespace phaco {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using Pointer = json::json_pointer;

const fs::path kSourceDir = PHACO_SOURCE_DIR;
constexpr uint64_t kDefaultSeed = 20261126;
// Release runs the full count; ASan+UBSan (5-20x slower) a fifth of it, still every kind of
// mutation.
const int kDefaultCount = test::asan_scaled(2400, 5);
constexpr double kMaxSimulatedS = 1.0;
constexpr uint64_t kMaxFrames = 60;              // 0.5 s at the shipped 1/120 s
constexpr double kTeleportSpeedMmPerS = 10'000;  // 10 m/s
// Replaced, in the dumped text, by a token JSON cannot hold as a value (1e999, NaN).
constexpr const char* kTextSentinel = "@@fuzz-text@@";

uint64_t env_u64(const char* name, uint64_t fallback) {
  const char* v = std::getenv(name);
  return v && *v ? std::strtoull(v, nullptr, 10) : fallback;
}

// splitmix64 of (seed, i): each mutation's own stream.
uint64_t mix(uint64_t seed, uint64_t i) {
  uint64_t z = seed + 0x9E3779B97F4A7C15ull * (i + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// Draws that are the same on every standard library (std:: distributions are not).
struct Rng {
  std::mt19937_64 gen;
  explicit Rng(uint64_t s) : gen(s) {}
  std::size_t pick(std::size_t n) { return n == 0 ? 0 : static_cast<std::size_t>(gen() % n); }
  double uniform() { return static_cast<double>(gen() >> 11) * 0x1p-53; }
  double between(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  bool chance(double p) { return uniform() < p; }
};

struct BaseFile {
  fs::path path;
  json doc;
};

std::vector<BaseFile> load_dir(const fs::path& dir) {
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.path().extension() == ".json") files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());  // directory order is not deterministic
  std::vector<BaseFile> out;
  for (const fs::path& f : files) {
    std::ifstream in(f);
    out.push_back({f, json::parse(in)});
  }
  return out;
}

void write_text(const fs::path& file, const std::string& text) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out << text;
}

struct Leaves {
  std::vector<Pointer> numbers, strings, arrays, members;
};

void collect(const json& j, const Pointer& at, Leaves& out) {
  if (j.is_number()) {
    out.numbers.push_back(at);
  } else if (j.is_string()) {
    out.strings.push_back(at);
  } else if (j.is_array()) {
    out.arrays.push_back(at);
    for (std::size_t i = 0; i < j.size(); ++i) collect(j[i], at / i, out);
  } else if (j.is_object()) {
    for (const auto& [k, v] : j.items()) {
      out.members.push_back(at / k);
      collect(v, at / k, out);
    }
  }
}

// The tracks of a scenario document, as pointers to their arrays.
std::vector<Pointer> tracks_of(const json& doc) {
  std::vector<Pointer> out;
  if (!doc.contains("hands") || !doc["hands"].is_object()) return out;
  for (const auto& [hand, h] : doc["hands"].items()) {
    if (h.is_object() && h.contains("track") && h["track"].is_array() && !h["track"].empty()) {
      out.push_back(Pointer("/hands") / hand / "track");
    }
  }
  return out;
}

// A value of another kind, or a number no file should carry.
json junk_value(Rng& rng) {
  switch (rng.pick(14)) {
    case 0:
      return nullptr;
    case 1:
      return "junk";
    case 2:
      return 1e300;
    case 3:
      return -1e300;
    case 4:
      return 0;
    case 5:
      return std::numeric_limits<uint64_t>::max();
    case 6:
      return std::numeric_limits<int64_t>::min();
    case 7:
      return 1.2e19;
    case 8:
      return -1;
    case 9:
      return 1e-300;
    case 10:
      return true;
    case 11:
      return json::array();
    case 12:
      return json::object();
    default:
      return kTextSentinel;  // ±1e999 or NaN in the text
  }
}

std::string mutate_once(json& doc, Rng& rng, bool scenario);

// One mutation of `doc`; returns its name for the failure message. A mutation that meets a part
// an earlier one broke (a track that is no longer an array) stops there: what it did stays.
std::string mutate(json& doc, Rng& rng, bool scenario) {
  try {
    return mutate_once(doc, rng, scenario);
  } catch (const json::exception&) {
    return "a mutation stopped by an earlier one";
  }
}

std::string mutate_once(json& doc, Rng& rng, bool scenario) {
  Leaves leaves;
  collect(doc, Pointer(), leaves);
  const std::vector<Pointer> tracks = scenario ? tracks_of(doc) : std::vector<Pointer>{};
  // How often each kind is drawn, in the order of the cases below: the kinds that break a file
  // more often than the kinds that keep it valid, so that most mutations end in validation.
  static constexpr std::array<int, 11> kWeights{4, 1, 3, 3, 3, 1, 1, 1, 1, 1, 1};
  int draw = static_cast<int>(rng.pick(std::accumulate(kWeights.begin(), kWeights.end(), 0u)));
  std::size_t kind = 0;
  while (draw >= kWeights[kind]) draw -= kWeights[kind++];
  switch (kind) {
    case 0:  // a number to junk, a huge magnitude, zero, or ±inf/NaN in the text
      if (leaves.numbers.empty()) break;
      doc[leaves.numbers[rng.pick(leaves.numbers.size())]] = junk_value(rng);
      return "number to junk";
    case 1: {  // a number scaled or shifted: mostly still valid, so it runs
      if (leaves.numbers.empty()) break;
      json& v = doc[leaves.numbers[rng.pick(leaves.numbers.size())]];
      const double x = v.get<double>();
      v = rng.chance(0.5) ? x * rng.between(-3, 3) : x + rng.between(-5, 5);
      return "number scaled";
    }
    case 2: {  // a string to junk
      if (leaves.strings.empty()) break;
      static const char* const kJunk[] = {"",
                                          " ",
                                          "forceps ",
                                          "phaco_probe",
                                          "hook",
                                          "aspirator",
                                          "x.y",
                                          "../../etc/passwd",
                                          "\xc3\xa9",
                                          "capsulorhexis",
                                          "corneal_incision",
                                          "phaco_sculpting",
                                          "easy",
                                          "hard"};
      doc[leaves.strings[rng.pick(leaves.strings.size())]] = kJunk[rng.pick(std::size(kJunk))];
      return "string to junk";
    }
    case 3: {  // an array truncated
      if (leaves.arrays.empty()) break;
      json& a = doc[leaves.arrays[rng.pick(leaves.arrays.size())]];
      a.erase(a.begin() + static_cast<std::ptrdiff_t>(rng.pick(a.size() + 1)), a.end());
      return "array truncated";
    }
    case 4: {  // a key removed
      if (leaves.members.empty()) break;
      const Pointer& p = leaves.members[rng.pick(leaves.members.size())];
      doc[p.parent_pointer()].erase(p.back());
      return "key removed";
    }
    case 5: {  // a track shuffled: samples out of order
      if (tracks.empty()) break;
      json& t = doc[tracks[rng.pick(tracks.size())]];
      std::shuffle(t.begin(), t.end(), rng.gen);
      return "track shuffled";
    }
    case 6: {  // positions shuffled between a track's samples: the times stay sorted, so it runs
      if (tracks.empty()) break;
      json& t = doc[tracks[rng.pick(tracks.size())]];
      std::vector<json> pos;
      for (const json& s : t) pos.push_back(s.value("pos", json()));
      std::shuffle(pos.begin(), pos.end(), rng.gen);
      for (std::size_t i = 0; i < t.size(); ++i) t[i]["pos"] = pos[i];
      return "track positions shuffled";
    }
    case 7: {  // a tool teleporting at 10 m/s: a sample inserted 1 ms after another, 10 mm away
      if (tracks.empty()) break;
      json& t = doc[tracks[rng.pick(tracks.size())]];
      const std::size_t k = rng.pick(t.size());
      const double t0 = t[k]["t"].get<double>();
      double dt = 1e-3;
      if (k + 1 < t.size()) dt = std::min(dt, 0.5 * (t[k + 1]["t"].get<double>() - t0));
      json sample = t[k];
      sample["t"] = t0 + dt;
      const double step = kTeleportSpeedMmPerS * dt;
      const double theta = rng.between(0, 2 * std::numbers::pi), z = rng.between(-1, 1);
      const double r = std::sqrt(1 - z * z);
      const std::array<double, 3> dir{r * std::cos(theta), r * std::sin(theta), z};
      for (std::size_t i = 0; i < 3; ++i) {
        const double x = sample["pos"][i].get<double>() + step * dir[i];
        sample["pos"][i] = std::clamp(x, -kWorkspaceHalfMm, kWorkspaceHalfMm);
      }
      t.insert(t.begin() + static_cast<std::ptrdiff_t>(k + 1), sample);
      return "teleport at 10 m/s";
    }
    case 8: {  // a tool jumping anywhere in the workspace within one sample
      if (tracks.empty()) break;
      json& t = doc[tracks[rng.pick(tracks.size())]];
      json& s = t[rng.pick(t.size())];
      for (int i = 0; i < 3; ++i) {
        s["pos"][i] = rng.between(-kWorkspaceHalfMm, kWorkspaceHalfMm);
      }
      return "jump across the workspace";
    }
    case 9: {  // an eye override, in range or just past it
      if (!scenario || (doc.contains("eye") && !doc["eye"].is_object())) break;
      const auto& ranges = eye::eye_param_ranges();
      const eye::EyeParamRange& r = ranges[rng.pick(ranges.size())];
      const double values[] = {r.lo,         r.hi,         rng.between(r.lo, r.hi),
                               r.lo * 0.999, r.hi * 1.001, 1e300};
      doc["eye"]["overrides"][std::string(r.key)] = values[rng.pick(std::size(values))];
      return "eye override " + std::string(r.key);
    }
    default: {  // a difficulty setting, in range or not
      static const char* const kSettings[] = {"patient_age_years", "anterior_bowing_kpa",
                                              "anterior_chamber_depth_mm", "nucleus_hardness"};
      const char* key = kSettings[rng.pick(std::size(kSettings))];
      const double v = rng.chance(0.7) ? rng.between(0, 5) : rng.between(-1e3, 1e3);
      if (scenario) {
        doc["difficulty"] = {{key, v}};
      } else if (doc.contains("difficulty") && doc["difficulty"].is_object() &&
                 doc["difficulty"].contains("default")) {
        const json& name = doc["difficulty"]["default"];
        if (name.is_string()) doc["difficulty"]["levels"][name.get<std::string>()][key] = v;
      }
      return std::string("difficulty ") + key;
    }
  }
  doc["fuzz_unknown_field"] = 1;  // nothing of the chosen kind: an unknown field instead
  return "unknown field";
}

// Text of `doc`, with the sentinel replaced by a token JSON has no value for.
std::string dump_with_text_tokens(const json& doc, Rng& rng) {
  std::string text = doc.dump(2);
  const std::string quoted = std::string("\"") + kTextSentinel + "\"";
  static const char* const kTokens[] = {"1e999", "-1e999", "NaN", "Infinity", "-inf"};
  for (std::size_t at = text.find(quoted); at != std::string::npos; at = text.find(quoted, at)) {
    text.replace(at, quoted.size(), kTokens[rng.pick(std::size(kTokens))]);
  }
  return text;
}

// The longest a mutation of a scenario with step dt_s may run.
double max_duration(double dt_s) {
  return std::min(kMaxSimulatedS, static_cast<double>(kMaxFrames) * dt_s);
}

// Level 0 and at most max_duration: half the time the whole track is played faster to fit (the
// tools then move up to 50 times as fast as the shipped hands: more cuts, tears and contacts).
void shorten(json& doc, Rng& rng) {
  const double duration = doc["duration_s"].get<double>();
  const double longest = max_duration(doc.value("dt_s", 1.0 / 120.0));
  if (duration > longest && rng.chance(0.5)) {
    const double f = longest / duration;
    for (const Pointer& t : tracks_of(doc)) {
      for (json& s : doc[t]) s["t"] = s["t"].get<double>() * f;
    }
  }
  doc["duration_s"] = std::min(duration, longest);
  doc["eye"]["level"] = 0;
}

// After a mutation that still parses: back to level 0 and the frame budget, in the file itself,
// so the file kept for a failure is what ran.
bool clamp_cost(json& doc, const Scenario& s) {
  const double longest = max_duration(s.dt_s);
  if (s.eye.level == 0 && s.duration_s <= longest) return false;
  doc["eye"]["level"] = 0;
  doc["duration_s"] = std::max(s.dt_s, std::min(s.duration_s, longest));
  return true;
}

// "FILE: where: ..." with FILE one of `files` and `where` a JSON path or a line and column.
bool names_a_field(const std::string& message, const std::vector<std::string>& files) {
  for (const std::string& f : files) {
    if (message.rfind(f + ": ", 0) != 0) continue;
    const std::string rest = message.substr(f.size() + 2);
    if (rest.rfind("line ", 0) == 0) return true;
    const std::size_t colon = rest.find(": ");
    if (colon == std::string::npos || colon == 0) return false;
    const std::string where = rest.substr(0, colon);
    return where.find(' ') == std::string::npos;
  }
  return false;
}

// Every floating-point number of the report finite ("" if so, else where it is not).
std::string non_finite_in(const json& j, const std::string& at) {
  if (j.is_number_float() && !std::isfinite(j.get<double>())) return at;
  if (j.is_array()) {
    for (std::size_t i = 0; i < j.size(); ++i) {
      if (auto w = non_finite_in(j[i], at + "[" + std::to_string(i) + "]"); !w.empty()) return w;
    }
  }
  if (j.is_object()) {
    for (const auto& [k, v] : j.items()) {
      if (auto w = non_finite_in(v, at + "." + k); !w.empty()) return w;
    }
  }
  return {};
}

// Runs the scenario as `phaco run` does; "" when it ends with a finite state and a complete report.
std::string run_and_check(const Scenario& s, const fs::path& cache_dir, double& build_s) {
  SceneOptions o;
  o.threads = 1;
  o.cache_dir = cache_dir;
  const auto t0 = std::chrono::steady_clock::now();
  auto scene = build_scene(s, o);
  build_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const uint64_t frames = s.frame_count();
  for (uint64_t f = 0; f < frames; ++f) step(*scene);
  const json report = to_json(report_of(*scene));
  if (scene->frame != frames) return "stopped at frame " + std::to_string(scene->frame);
  for (Entity e : scene->bodies) {
    if (const Particles* p = scene->world.get<Particles>(e); p && !test::all_finite(*p)) {
      return "non-finite particle in " + scene->world.name(e);
    }
  }
  for (Entity e : scene->tools) {
    const ToolState& t = scene->world.at<ToolState>(e);
    if (!t.pos.allFinite() || !t.quat.coeffs().allFinite() || !std::isfinite(t.grip) ||
        !std::isfinite(t.pedal)) {
      return "non-finite tool pose of " + scene->world.name(e);
    }
  }
  if (const std::string w = non_finite_in(report, "report"); !w.empty()) return "non-finite " + w;
  if (!report["metrics"].contains("score") || !report["metrics"]["score"].is_number()) {
    return "report without a score";
  }
  if (report["frames"].get<uint64_t>() != frames ||
      report["state_hash"].get<std::string>().empty()) {
    return "incomplete report";
  }
  return {};
}

TEST(ScenarioFuzz, MutationsAreRefusedNamingAFieldOrRunToAFiniteEnd) {
  const uint64_t seed = env_u64("PHACO_FUZZ_SEED", kDefaultSeed);
  const int count = static_cast<int>(env_u64("PHACO_FUZZ_COUNT", kDefaultCount));
  const fs::path dir = fs::temp_directory_path() / ("phaco-scenario-fuzz-" + std::to_string(seed));
  fs::create_directories(dir);
  const fs::path running = dir / "running.json", drill_file = dir / "drill.json";
  // Its own mesh cache: geometric overrides make level-0 meshes (0.2 s each) that no other test
  // wants, so they go with the fuzzer's folder.
  const fs::path cache_dir = dir / "mesh-cache";
  std::printf(
      "scenario fuzz: seed %llu (PHACO_FUZZ_SEED), %d mutations (PHACO_FUZZ_COUNT); a "
      "signal or hang was running %s\n",
      static_cast<unsigned long long>(seed), count, running.c_str());

  const std::vector<BaseFile> scenarios = load_dir(kSourceDir / "data/scenarios");
  const std::vector<BaseFile> drills = load_dir(kSourceDir / "data/drills");
  ASSERT_GE(scenarios.size(), 10u);
  ASSERT_GE(drills.size(), 3u);

  int refused = 0, ran = 0, failures = 0;
  double run_s = 0, build_s = 0;
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < count; ++i) {
    Rng rng(mix(seed, static_cast<uint64_t>(i)));
    const bool drill_mutation = rng.chance(0.3);
    json doc;
    std::vector<std::string> files;  // what an error may name
    std::string what;
    const std::string source = (dir / ("mutation-" + std::to_string(i) + ".json")).string();
    std::string text;
    if (drill_mutation) {
      const BaseFile& d = drills[rng.pick(drills.size())];
      json drill = d.doc;
      what = "drill " + d.path.filename().string() + ": " + mutate(drill, rng, false);
      write_text(drill_file, dump_with_text_tokens(drill, rng));
      std::vector<const BaseFile*> same;
      for (const BaseFile& s : scenarios) {
        if (s.doc["drill"] == d.doc["drill"]) same.push_back(&s);
      }
      doc = same[rng.pick(same.size())]->doc;
      doc["drill_file"] = drill_file.string();
      shorten(doc, rng);
      files = {source, drill_file.string()};
      text = doc.dump(2);
    } else {
      const BaseFile& b = scenarios[rng.pick(scenarios.size())];
      doc = b.doc;
      shorten(doc, rng);
      what = b.path.filename().string() + ": " + mutate(doc, rng, true);
      if (rng.chance(0.3)) what += ", " + mutate(doc, rng, true);
      files = {source};
      text = dump_with_text_tokens(doc, rng);
    }

    // `phaco validate`: the scenario, then what the run reads before its meshes.
    std::optional<Scenario> scenario;
    try {
      Scenario s = parse_scenario(text, source, kSourceDir / "data/scenarios");
      if (clamp_cost(doc, s)) {
        text = doc.dump(2);
        s = parse_scenario(text, source, kSourceDir / "data/scenarios");
      }
      check_scene_inputs(s);
      scenario = std::move(s);
    } catch (const InputError& e) {
      ++refused;
      if (!names_a_field(e.what(), files)) {
        ++failures;
        write_text(source, text);
        ADD_FAILURE() << "mutation " << i << " (" << what
                      << "): the error names no field: " << e.what() << "\n  file: " << source;
      }
      continue;
    }

    // `phaco run`: build, step to the end, report.
    ++ran;
    write_text(running, text);
    std::string problem;
    const auto t0 = std::chrono::steady_clock::now();
    try {
      problem = run_and_check(*scenario, cache_dir, build_s);
    } catch (const InputError& e) {
      problem =
          std::string("input error only the run found (exit 2 after validate passed): ") + e.what();
    } catch (const std::exception& e) {
      problem = std::string("internal error (exit 1): ") + e.what();
    }
    run_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!problem.empty()) {
      ++failures;
      write_text(source, text);
      if (drill_mutation) {  // keep the drill file beside it, where the scenario points
        fs::copy_file(drill_file, dir / ("mutation-" + std::to_string(i) + ".drill.json"),
                      fs::copy_options::overwrite_existing);
        doc["drill_file"] = (dir / ("mutation-" + std::to_string(i) + ".drill.json")).string();
        write_text(source, doc.dump(2));
      }
      ADD_FAILURE() << "mutation " << i << " (" << what << "): " << problem
                    << "\n  reproduce: phaco run " << source;
    }
  }
  const double total_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf(
      "scenario fuzz: %d mutations: %d refused naming a field, %d validated and ran "
      "(%.1f s, of which %.1f s building scenes), %d failures; %.1f s in all\n",
      count, refused, ran, run_s, build_s, failures, total_s);
  fs::remove_all(cache_dir);
  if (failures == 0) fs::remove_all(dir);

  // The fuzzer exercises both outcomes, or it proves nothing.
  EXPECT_EQ(refused + ran, count);
  if (count >= 100) {
    EXPECT_GT(refused, count / 4) << "too few mutations reach validation's errors";
    EXPECT_GT(ran, count / 50) << "too few mutations run";
  }
}

}  // namespace
}  // namespace phaco
