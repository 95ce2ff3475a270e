#pragma once
// Where OpenPhaco keeps a user's own files, after the XDG base directory specification: the mesh
// cache in $XDG_CACHE_HOME/openphaco (default ~/.cache/openphaco), the records database in
// $XDG_DATA_HOME/openphaco (default ~/.local/share/openphaco), the trainer's settings in
// $XDG_CONFIG_HOME/openphaco (default ~/.config/openphaco). A relative $XDG_* is ignored, as the
// specification says. Nothing is created here: writers call writable_dir() first.
#include <filesystem>
#include <string>

namespace phaco::io {

enum class UserDir { Cache, Data, Config };

// The folder, or throws InputError naming the variables to set when neither the XDG variable nor
// $HOME is usable.
std::filesystem::path user_dir(UserDir which);

// Creates dir (and its parents) if needed and checks a file can be made in it; throws InputError
// "cannot write to FOLDER (<what>): <reason>; <hint>" otherwise, naming the folder.
void writable_dir(const std::filesystem::path& dir, const std::string& what,
                  const std::string& hint);

}  // namespace phaco::io
