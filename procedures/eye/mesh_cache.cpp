#include "procedures/eye/mesh_cache.hpp"

#include <unistd.h>

#include <atomic>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <system_error>

#include "engine/core/error.hpp"
#include "engine/io/mesh_obj.hpp"
#include "engine/io/tetgen_files.hpp"
#include "engine/io/text_lines.hpp"
#include "engine/io/user_dirs.hpp"

namespace phaco::eye {
namespace fs = std::filesystem;
namespace {

// Bump when a generator changes its output, so stale entries are not reused.
constexpr int kGeneratorVersion = 1;
constexpr const char* kMetaFile = "meta.json";

bool is_geometric(const std::string& key) {
  for (const char* prefix : {"lens.", "iris.", "cornea.", "globe."}) {
    if (key.rfind(prefix, 0) == 0) return true;
  }
  return key == "capsule.radius_mm";
}

// FNV-1a, 64 bit: stable across runs and platforms, unlike std::hash.
uint64_t fnv1a(const std::string& text) {
  uint64_t h = 14695981039346656037ull;
  for (unsigned char c : text) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

std::string unique_suffix() {
  static std::atomic<uint64_t> counter{0};
  return std::to_string(::getpid()) + "-" + std::to_string(counter++);
}

}  // namespace

std::string cache_key(const EyeParams& params, const Resolution& res, CapsuleLayout layout) {
  // Built by appending: GCC 12 warns falsely (-Wrestrict) on chains of "literal" + std::string.
  std::string text;
  for (const auto& part : {std::to_string(kGeneratorVersion), std::to_string(res.level),
                           std::to_string(res.capsule_vertices), std::to_string(res.lens_tets),
                           std::string(to_string(layout))}) {
    text += part;
    text += ';';
  }
  for (const auto& [key, value] : params.values) {  // std::map: sorted, so the order is fixed
    if (!is_geometric(key)) continue;
    text += key;
    text += '=';
    text::append_number(text, value);
    text += ';';
  }
  char key[96];
  std::snprintf(key, sizeof key, "L%d-%s-%016llx", res.level, to_string(layout),
                static_cast<unsigned long long>(fnv1a(text)));
  return key;
}

MeshCache::MeshCache(fs::path dir) : dir_(std::move(dir)) {}

fs::path MeshCache::entry_dir(const EyeParams& params, const Resolution& res,
                              CapsuleLayout layout) const {
  return dir_ / cache_key(params, res, layout);
}

EyeMeshes MeshCache::load_or_build(const EyeParams& params, const Resolution& res,
                                   CapsuleLayout layout, bool with_lens_tets) {
  const fs::path entry = entry_dir(params, res, layout);
  std::error_code ec;
  const bool complete = fs::exists(entry / kMetaFile, ec);
  if (complete && (!with_lens_tets || fs::exists(entry / "lens.ele", ec))) {
    try {
      return read_eye_meshes(entry, res, with_lens_tets);
    } catch (const InputError&) {
      // A damaged entry (edited or truncated by hand) is rebuilt below.
    }
  }

  EyeMeshes meshes = make_eye_meshes(params, res, layout, with_lens_tets);
  ++builds_;

  const std::string key = entry.filename().string();
  io::writable_dir(dir_, "the mesh cache",
                   "set PHACO_CACHE_DIR or XDG_CACHE_HOME to a writable folder");
  const fs::path tmp = dir_ / (key + ".tmp-" + unique_suffix());
  fs::create_directories(tmp, ec);
  if (ec) {
    throw InputError("cannot create mesh cache directory " + tmp.string() + ": " + ec.message() +
                     " (set PHACO_CACHE_DIR to a writable directory)");
  }
  write_eye_meshes(meshes, tmp);
  nlohmann::json meta;
  meta["key"] = key;
  meta["generator_version"] = kGeneratorVersion;
  meta["level"] = res.level;
  meta["layout"] = to_string(layout);
  meta["lens_tets"] = with_lens_tets;
  meta["params"] = params.values;
  text::write_file(tmp / kMetaFile, meta.dump(2) + "\n");

  if (fs::exists(entry, ec)) {
    // Replace an entry lacking tets (or damaged): move it aside first, as rename onto a non-empty
    // directory fails.
    const fs::path old = dir_ / (key + ".old-" + unique_suffix());
    fs::rename(entry, old, ec);
    fs::rename(tmp, entry, ec);
    fs::remove_all(ec ? tmp : old, ec);
  } else {
    fs::rename(tmp, entry, ec);
    if (ec) fs::remove_all(tmp, ec);  // another process installed the same entry first
  }
  return meshes;
}

fs::path MeshCache::default_dir() {
  if (const char* env = std::getenv("PHACO_CACHE_DIR"); env != nullptr && *env != '\0') return env;
  try {
    return io::user_dir(io::UserDir::Cache) / "meshes";
  } catch (const InputError&) {
    return fs::temp_directory_path() / "openphaco" / "meshes";  // no $HOME: a cache still helps
  }
}

void write_eye_meshes(const EyeMeshes& meshes, const fs::path& dir) {
  fs::create_directories(dir);
  write_obj(dir / "cornea.obj", meshes.cornea);
  write_obj(dir / "capsule.obj", meshes.capsule);
  write_obj(dir / "iris.obj", meshes.iris);
  write_obj(dir / "globe.obj", meshes.globe);
  write_obj(dir / "lens_surface.obj", meshes.lens_surface);
  if (meshes.lens_tets) write_tetgen(dir / "lens", *meshes.lens_tets);
}

EyeMeshes read_eye_meshes(const fs::path& dir, const Resolution& res, bool with_lens_tets) {
  EyeMeshes m;
  m.res = res;
  m.cornea = read_obj(dir / "cornea.obj");
  m.capsule = read_obj(dir / "capsule.obj");
  m.iris = read_obj(dir / "iris.obj");
  m.globe = read_obj(dir / "globe.obj");
  m.lens_surface = read_obj(dir / "lens_surface.obj");
  if (with_lens_tets) m.lens_tets = read_tetgen(dir / "lens");
  return m;
}

}  // namespace phaco::eye
