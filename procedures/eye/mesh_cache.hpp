#pragma once
// On-disk cache of generated eye meshes. TetGen at high levels takes seconds to minutes, so the
// meshes are generated once per (level, capsule layout, geometry) and read back afterwards.
//
// Layout: <dir>/<key>/{cornea,capsule,iris,globe,lens_surface}.obj, lens.node, lens.ele, meta.json
// key = "L<level>-<layout>-<16 hex digits>", the hash covering the resolution targets, a generator
// version and every geometric parameter (lens.*, iris.*, cornea.*, globe.*, capsule.radius_mm), so
// a geometric override gets its own entry while material overrides reuse it.
// An entry is written into a temporary sibling directory and renamed into place: a crash leaves
// no half entry under the key, and concurrent writers of the same key keep whichever won.
#include <cstddef>
#include <filesystem>
#include <string>

#include "procedures/eye/eye_mesh.hpp"

namespace phaco::eye {

std::string cache_key(const EyeParams& params, const Resolution& res, CapsuleLayout layout);

class MeshCache {
 public:
  explicit MeshCache(std::filesystem::path dir);

  // Loads the entry if it is complete (and holds lens tets when asked for); otherwise generates
  // the meshes, writes the entry and returns them. lens_tets is set exactly when with_lens_tets.
  EyeMeshes load_or_build(const EyeParams& params, const Resolution& res, CapsuleLayout layout,
                          bool with_lens_tets);

  std::filesystem::path entry_dir(const EyeParams& params, const Resolution& res,
                                  CapsuleLayout layout) const;
  const std::filesystem::path& dir() const { return dir_; }
  // How many times this cache generated meshes instead of loading them.
  size_t builds() const { return builds_; }

  // env PHACO_CACHE_DIR, else $XDG_CACHE_HOME/openphaco/meshes, else ~/.cache/openphaco/meshes
  // (engine/io/user_dirs.hpp); without $HOME, the temporary folder's openphaco/meshes.
  static std::filesystem::path default_dir();

 private:
  std::filesystem::path dir_;
  size_t builds_ = 0;
};

// Writes every mesh of `meshes` into dir (created if needed): the files named above, no meta.json.
// Used by the cache and by `phaco mesh --level L --out DIR`.
void write_eye_meshes(const EyeMeshes& meshes, const std::filesystem::path& dir);

// Reads what write_eye_meshes wrote; the tets only when with_lens_tets. Throws InputError.
EyeMeshes read_eye_meshes(const std::filesystem::path& dir, const Resolution& res,
                          bool with_lens_tets);

}  // namespace phaco::eye
