#include "procedures/procedure/procedure_file.hpp"

#include <fstream>
#include <sstream>

#include "engine/core/error.hpp"
#include "engine/io/json_reader.hpp"
#include "procedures/eye/resolution.hpp"

namespace phaco {

namespace {

std::string read_text(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file.string() + ": cannot open the file");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

Scenario read_step(const io::JsonReader& r, const nlohmann::json& v, const std::string& path,
                   const std::filesystem::path& base_dir) {
  r.expect_object(v, path, {"scenario", "duration_s"});
  const std::string rel =
      r.string(r.require(v, path, "scenario", "a scenario file"), io::path_key(path, "scenario"));
  const std::filesystem::path file = base_dir / rel;
  if (!std::filesystem::exists(file))
    r.fail(io::path_key(path, "scenario"), "no scenario file at " + file.string());
  Scenario s = load_scenario(file);
  if (const auto* d = io::JsonReader::find(v, "duration_s")) {
    s.duration_s = r.number_in(*d, io::path_key(path, "duration_s"), s.dt_s, s.duration_s);
  }
  return s;
}

}  // namespace

bool is_procedure_file(const std::filesystem::path& file) {
  try {
    const nlohmann::json j = nlohmann::json::parse(read_text(file));
    return j.is_object() && j.contains("steps");
  } catch (const std::exception&) {
    return false;
  }
}

Procedure parse_procedure(std::string_view text, const std::string& source,
                          const std::filesystem::path& base_dir) {
  const nlohmann::json j = io::parse_json_text(text, source);
  const io::JsonReader r(source);
  r.expect_object(j, "$", {"name", "description", "level", "difficulty", "steps"});
  Procedure p;
  p.source = source;
  if (const auto* n = io::JsonReader::find(j, "name")) p.name = r.string(*n, "name");
  if (const auto* d = io::JsonReader::find(j, "description"))
    p.description = r.string(*d, "description");
  const nlohmann::json& steps =
      r.array(r.require(j, "$", "steps", "an array of steps"), "steps", "steps");
  if (steps.empty()) r.fail("steps", "expected at least one step, got none");
  for (size_t i = 0; i < steps.size(); ++i) {
    const std::string path = io::path_index("steps", i);
    Scenario s = read_step(r, steps[i], path, base_dir);
    if (!p.steps.empty() && s.drill <= p.steps.back().drill) {
      r.fail(io::path_key(path, "scenario"),
             "the steps go in the operation's order (corneal_incision, capsulorhexis, "
             "phaco_sculpting, nucleus_removal), each once; got " +
                 std::string(to_string(s.drill)) + " after " +
                 std::string(to_string(p.steps.back().drill)));
    }
    if (!p.steps.empty()) s.eye = p.steps.front().eye;  // one eye: the first step's
    p.steps.push_back(std::move(s));
  }
  if (const auto* l = io::JsonReader::find(j, "level")) {
    const int level = static_cast<int>(r.integer_in(*l, "level", eye::kMinLevel, eye::kMaxLevel));
    for (Scenario& s : p.steps) s.eye.level = level;
  }
  if (const auto* d = io::JsonReader::find(j, "difficulty")) {
    const std::string level = r.string(*d, "difficulty");
    for (Scenario& s : p.steps) s.difficulty = level;
  }
  return p;
}

Procedure load_procedure(const std::filesystem::path& file) {
  return parse_procedure(read_text(file), file.string(), file.parent_path());
}

}  // namespace phaco
