#include "engine/io/user_dirs.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>

#include "engine/core/error.hpp"

namespace phaco::io {

namespace fs = std::filesystem;

namespace {

struct Spec {
  const char* variable;  // XDG_CACHE_HOME ...
  const char* fallback;  // below $HOME
};

Spec spec_of(UserDir which) {
  switch (which) {
    case UserDir::Cache:
      return {"XDG_CACHE_HOME", ".cache"};
    case UserDir::Data:
      return {"XDG_DATA_HOME", ".local/share"};
    case UserDir::Config:
      return {"XDG_CONFIG_HOME", ".config"};
  }
  return {"XDG_DATA_HOME", ".local/share"};
}

}  // namespace

fs::path user_dir(UserDir which) {
  const Spec s = spec_of(which);
  if (const char* xdg = std::getenv(s.variable); xdg && *xdg && fs::path(xdg).is_absolute())
    return fs::path(xdg) / "openphaco";
  if (const char* home = std::getenv("HOME"); home && *home && fs::path(home).is_absolute())
    return fs::path(home) / s.fallback / "openphaco";
  throw InputError(std::string("no folder for OpenPhaco's files: neither $") + s.variable +
                   " nor $HOME is set to an absolute path");
}

void writable_dir(const fs::path& dir, const std::string& what, const std::string& hint) {
  const auto fail = [&](const std::string& reason) {
    throw InputError("cannot write to " + dir.string() + " (" + what + "): " + reason +
                     (hint.empty() ? "" : "; " + hint));
  };
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) fail(ec.message());
  if (!fs::is_directory(dir, ec)) fail("not a folder");
  // access(W_OK) answers for this process's user, also where the folder exists already.
  if (::access(dir.c_str(), W_OK | X_OK) != 0) fail(std::strerror(errno));
}

}  // namespace phaco::io
