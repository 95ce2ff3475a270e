#include "apps/phaco/compare_command.hpp"

#include <cstdio>
#include <fstream>

#include "apps/phaco/args.hpp"
#include "apps/phaco/commands.hpp"
#include "engine/core/error.hpp"
#include "procedures/compare/compare.hpp"

namespace phaco::cli {

int compare(const std::vector<std::string>& raw) {
  const Args a = parse_args("compare", raw, {"--json"}, {});
  if (a.positional.size() != 2) {
    throw InputError(
        "compare: give the run report and the expert's (phaco compare RUN.json "
        "EXPERT.json [--json OUT.json])");
  }
  const compare::Comparison c = compare::compare_files(a.positional[0], a.positional[1]);
  if (auto out = a.option("--json")) {
    std::ofstream file(*out);
    if (!file) throw InputError("compare: cannot write '" + *out + "'");
    file << compare::to_json(c).dump(2) << "\n";
    if (!file.flush()) throw InputError("compare: cannot write '" + *out + "'");
  }
  std::fputs(compare::summary_text(c).c_str(), stdout);
  if (auto out = a.option("--json")) std::printf("comparison written to %s\n", out->c_str());
  return kOk;
}

}  // namespace phaco::cli
