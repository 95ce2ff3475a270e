#include <fstream>

#include "perf/machine.hpp"
#include "perf/report.hpp"
#include "perf/studies.hpp"

namespace phaco::perf {

void regenerate_results(const std::filesystem::path& out_dir) {
  const std::string md =
      assemble_results(out_dir / "results", machine_markdown(describe_machine()));
  std::ofstream(out_dir / "RESULTS.md") << md;
}

}  // namespace phaco::perf
