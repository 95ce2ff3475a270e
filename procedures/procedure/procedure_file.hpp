#pragma once
// Procedure files (issue 20 item 1, docs/procedures.md): the whole operation in one eye, as a
// list of steps, each a drill scenario (data/scenarios) run on the eye the steps before it left:
//
//   { "name": "...", "description": "...", "level": 1, "difficulty": "standard",
//     "steps": [ { "scenario": "../scenarios/corneal_incision_expert.json" },
//                { "scenario": "../scenarios/capsulorhexis_expert.json", "duration_s": 11 }, ... ]
//                }
//
// The steps' drills come in the operation's order (corneal incision, capsulorhexis, phaco
// sculpting, nucleus removal), each at most once; a procedure may leave some out. One eye: the
// first step's eye (its parameters, overrides and capsule layout) is every step's, at "level" if
// given; "difficulty" (a level every drill file has) replaces each step's. "duration_s" cuts a
// step short (at most its scenario's duration). Errors name the file and JSON path (exit 2).
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "engine/io/scenario.hpp"

namespace phaco {

struct Procedure {
  std::string source;  // the file as given, for messages
  std::string name, description;
  std::vector<Scenario> steps;  // in order, one eye, each with the step's duration
};

// Whether `file` holds a procedure (a JSON object with "steps") rather than a scenario. False for
// a file that cannot be read or parsed (its loader then says why).
bool is_procedure_file(const std::filesystem::path& file);

// Reads and checks a procedure and its steps' scenarios. Throws InputError.
Procedure load_procedure(const std::filesystem::path& file);
Procedure parse_procedure(std::string_view json_text, const std::string& source,
                          const std::filesystem::path& base_dir);

}  // namespace phaco
