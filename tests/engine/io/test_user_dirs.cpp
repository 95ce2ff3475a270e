// The user's folders after the XDG base directories (issue 23): each variable wins over $HOME, a
// relative one is ignored, no usable variable is a named error, and a folder that cannot be
// written is named in the error.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>

#include "engine/core/error.hpp"
#include "engine/io/user_dirs.hpp"

namespace {

namespace fs = std::filesystem;
using phaco::InputError;
using phaco::io::user_dir;
using phaco::io::UserDir;

// Sets (or, with nullopt, unsets) a variable for the test's scope, then restores it.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, std::optional<std::string> value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    if (value)
      ::setenv(name, value->c_str(), 1);
    else
      ::unsetenv(name);
  }
  ~ScopedEnv() {
    if (old_)
      ::setenv(name_, old_->c_str(), 1);
    else
      ::unsetenv(name_);
  }

 private:
  const char* name_;
  std::optional<std::string> old_;
};

std::string error_of(const auto& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(UserDirs, XdgVariablesWinOverHome) {
  const ScopedEnv home("HOME", "/home/trainee");
  const ScopedEnv cache("XDG_CACHE_HOME", "/var/cache/t");
  const ScopedEnv data("XDG_DATA_HOME", std::nullopt);
  const ScopedEnv config("XDG_CONFIG_HOME", "relative/config");  // ignored: not absolute
  EXPECT_EQ(user_dir(UserDir::Cache), fs::path("/var/cache/t/openphaco"));
  EXPECT_EQ(user_dir(UserDir::Data), fs::path("/home/trainee/.local/share/openphaco"));
  EXPECT_EQ(user_dir(UserDir::Config), fs::path("/home/trainee/.config/openphaco"));
}

TEST(UserDirs, NoHomeAndNoXdgIsANamedError) {
  const ScopedEnv home("HOME", std::nullopt);
  const ScopedEnv config("XDG_CONFIG_HOME", std::nullopt);
  const std::string e = error_of([] { user_dir(UserDir::Config); });
  EXPECT_NE(e.find("$XDG_CONFIG_HOME"), std::string::npos) << e;
  EXPECT_NE(e.find("$HOME"), std::string::npos) << e;
}

TEST(UserDirs, AFolderThatCannotBeWrittenIsNamed) {
  const fs::path tmp =
      fs::temp_directory_path() / ("phaco-user-dirs-" + std::to_string(::getpid()));
  fs::remove_all(tmp);
  fs::create_directories(tmp);
  phaco::io::writable_dir(tmp / "a" / "b", "the mesh cache", "set PHACO_CACHE_DIR");
  EXPECT_TRUE(fs::is_directory(tmp / "a" / "b"));

  std::ofstream(tmp / "file") << "not a folder";
  const fs::path below_file = tmp / "file" / "cache";
  const std::string e = error_of(
      [&] { phaco::io::writable_dir(below_file, "the mesh cache", "set PHACO_CACHE_DIR"); });
  EXPECT_NE(e.find("cannot write to " + below_file.string() + " (the mesh cache)"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("set PHACO_CACHE_DIR"), std::string::npos) << e;
  fs::remove_all(tmp);
}

}  // namespace
