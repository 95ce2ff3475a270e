#include "procedures/eye/data_dir.hpp"

#include <algorithm>
#include <cstdlib>

#include "engine/core/error.hpp"

#if !defined(PHACO_SOURCE_DATA_DIR) || !defined(PHACO_BUILD_TREE)
#error \
    "PHACO_SOURCE_DATA_DIR and PHACO_BUILD_TREE must be defined by the build (procedures/CMakeLists.txt)"
#endif

namespace phaco::eye {

namespace fs = std::filesystem;

namespace {

// A file every data folder has: a folder without it is not one (an unrelated share/openphaco).
constexpr const char* kMarker = "eye/standard_eye.json";

bool holds_data(const fs::path& dir) {
  std::error_code ec;
  return fs::is_regular_file(dir / kMarker, ec);
}

// True when `path` is `dir` or below it, after resolving links and dot-dots.
bool inside(const fs::path& path, const fs::path& dir) {
  std::error_code ec;
  const fs::path p = fs::weakly_canonical(path, ec);
  const fs::path d = fs::weakly_canonical(dir, ec);
  if (ec || d.empty()) return false;
  return std::mismatch(d.begin(), d.end(), p.begin(), p.end()).first == d.end();
}

}  // namespace

DataDir locate_data_dir() {
  if (const char* env = std::getenv("PHACO_DATA_DIR"); env != nullptr && *env != '\0') {
    return {fs::path(env), "PHACO_DATA_DIR"};
  }
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  const fs::path installed =
      ec ? fs::path() : (exe.parent_path().parent_path() / "share" / "openphaco");
  if (!installed.empty() && holds_data(installed)) return {installed, "installed"};
  const fs::path source(PHACO_SOURCE_DATA_DIR);
  if (!ec && inside(exe, PHACO_BUILD_TREE) && holds_data(source)) return {source, "build tree"};
  throw InputError("cannot find OpenPhaco's data (" + std::string(kMarker) + "): not in " +
                   (installed.empty() ? std::string("the executable's ../share/openphaco")
                                      : installed.string()) +
                   "; set PHACO_DATA_DIR to the folder holding eye/, drills/ and scenarios/");
}

fs::path data_dir() {
  return locate_data_dir().dir;
}

}  // namespace phaco::eye
