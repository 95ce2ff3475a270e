#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>

#include "engine/core/error.hpp"
#include "eye_test_util.hpp"
#include "procedures/eye/mesh_cache.hpp"

namespace phaco::eye {
namespace {
namespace fs = std::filesystem;

void expect_same(const SurfaceMesh& a, const SurfaceMesh& b, const char* what) {
  EXPECT_EQ(a.vertices, b.vertices) << what;  // exact: OBJ keeps every bit
  EXPECT_EQ(a.triangles, b.triangles) << what;
}

void expect_same(const EyeMeshes& a, const EyeMeshes& b) {
  expect_same(a.cornea, b.cornea, "cornea");
  expect_same(a.capsule, b.capsule, "capsule");
  expect_same(a.iris, b.iris, "iris");
  expect_same(a.globe, b.globe, "globe");
  expect_same(a.lens_surface, b.lens_surface, "lens surface");
  ASSERT_EQ(a.lens_tets.has_value(), b.lens_tets.has_value());
  if (a.lens_tets) {
    EXPECT_EQ(a.lens_tets->vertices, b.lens_tets->vertices);
    EXPECT_EQ(a.lens_tets->tets, b.lens_tets->tets);
    EXPECT_EQ(a.lens_tets->region, b.lens_tets->region);
  }
}

size_t entries(const fs::path& dir) {
  size_t n = 0;
  for (const auto& e : fs::directory_iterator(dir)) n += e.is_directory() ? 1 : 0;
  return n;
}

TEST(MeshCache, RoundTripAndNoRebuild) {
  test::ScratchDir dir("mesh_cache");
  const EyeParams p = default_eye_params();
  const Resolution res = resolution_for_level(1);
  MeshCache cache(dir.path());
  const EyeMeshes built = cache.load_or_build(p, res, CapsuleLayout::Curvilinear, true);
  EXPECT_EQ(cache.builds(), 1u);
  ASSERT_TRUE(built.lens_tets.has_value());
  const fs::path entry = cache.entry_dir(p, res, CapsuleLayout::Curvilinear);
  for (const char* f : {"cornea.obj", "capsule.obj", "iris.obj", "globe.obj", "lens_surface.obj",
                        "lens.node", "lens.ele", "meta.json"}) {
    EXPECT_TRUE(fs::exists(entry / f)) << f;
  }
  EXPECT_EQ(entries(dir.path()), 1u) << "no temporary directory left behind";
  const auto stamp = fs::last_write_time(entry / "lens.ele");

  const EyeMeshes loaded = cache.load_or_build(p, res, CapsuleLayout::Curvilinear, true);
  EXPECT_EQ(cache.builds(), 1u) << "second call loads";
  EXPECT_EQ(fs::last_write_time(entry / "lens.ele"), stamp);
  expect_same(built, loaded);

  // A fresh cache object over the same directory also loads; without tets it skips them.
  MeshCache again(dir.path());
  const EyeMeshes surfaces = again.load_or_build(p, res, CapsuleLayout::Curvilinear, false);
  EXPECT_EQ(again.builds(), 0u);
  EXPECT_FALSE(surfaces.lens_tets.has_value());
  expect_same(surfaces.capsule, built.capsule, "capsule");
}

TEST(MeshCache, SurfaceOnlyEntryGainsTetsWhenAsked) {
  test::ScratchDir dir("mesh_cache_tets");
  const EyeParams p = default_eye_params();
  const Resolution res = resolution_for_level(0);
  MeshCache cache(dir.path());
  cache.load_or_build(p, res, CapsuleLayout::Isotropic, false);
  const fs::path entry = cache.entry_dir(p, res, CapsuleLayout::Isotropic);
  EXPECT_FALSE(fs::exists(entry / "lens.ele"));
  const EyeMeshes with = cache.load_or_build(p, res, CapsuleLayout::Isotropic, true);
  EXPECT_EQ(cache.builds(), 2u);
  ASSERT_TRUE(with.lens_tets.has_value());
  EXPECT_TRUE(fs::exists(entry / "lens.ele"));
  EXPECT_EQ(entries(dir.path()), 1u) << "the old entry was replaced, not kept beside";
  cache.load_or_build(p, res, CapsuleLayout::Isotropic, true);
  EXPECT_EQ(cache.builds(), 2u);
}

TEST(MeshCache, DamagedEntryIsRebuilt) {
  test::ScratchDir dir("mesh_cache_damaged");
  const EyeParams p = default_eye_params();
  const Resolution res = resolution_for_level(0);
  MeshCache cache(dir.path());
  const EyeMeshes built = cache.load_or_build(p, res, CapsuleLayout::Curvilinear, false);
  const fs::path entry = cache.entry_dir(p, res, CapsuleLayout::Curvilinear);
  std::ofstream(entry / "iris.obj") << "v 1 2 nan\n";
  const EyeMeshes again = cache.load_or_build(p, res, CapsuleLayout::Curvilinear, false);
  EXPECT_EQ(cache.builds(), 2u);
  expect_same(built.iris, again.iris, "iris");
  expect_same(built.iris, read_eye_meshes(entry, res, false).iris, "rewritten iris");
}

TEST(MeshCache, KeyFollowsGeometryLevelAndLayout) {
  const EyeParams p = default_eye_params();
  const Resolution r2 = resolution_for_level(2);
  const std::string base = cache_key(p, r2, CapsuleLayout::Curvilinear);
  EXPECT_EQ(base, cache_key(default_eye_params(), r2, CapsuleLayout::Curvilinear)) << "stable";
  EXPECT_EQ(base.rfind("L2-curvilinear-", 0), 0u) << base;
  EXPECT_NE(base, cache_key(p, resolution_for_level(3), CapsuleLayout::Curvilinear));
  EXPECT_NE(base, cache_key(p, r2, CapsuleLayout::Isotropic));

  EyeParams geometric = p;
  apply_override(geometric, "cornea.anterior_radius_mm", 7.7);
  EXPECT_NE(base, cache_key(geometric, r2, CapsuleLayout::Curvilinear));
  EyeParams rim = p;
  apply_override(rim, "capsule.radius_mm", 4.4);
  EXPECT_NE(base, cache_key(rim, r2, CapsuleLayout::Curvilinear));
  EyeParams material = p;
  apply_override(material, "capsule.youngs_modulus_kpa", 3000);
  EXPECT_EQ(base, cache_key(material, r2, CapsuleLayout::Curvilinear))
      << "material overrides reuse the meshes";
}

TEST(MeshCache, DefaultDirFollowsEnvironment) {
  const char* old = std::getenv("PHACO_CACHE_DIR");
  const std::string saved = old ? old : "";
  ::setenv("PHACO_CACHE_DIR", "/tmp/phaco-cache-test", 1);
  EXPECT_EQ(MeshCache::default_dir(), fs::path("/tmp/phaco-cache-test"));
  ::unsetenv("PHACO_CACHE_DIR");
  const char* xdg = std::getenv("XDG_CACHE_HOME");
  const std::string saved_xdg = xdg ? xdg : "";
  ::setenv("XDG_CACHE_HOME", "/tmp/xdg", 1);
  EXPECT_EQ(MeshCache::default_dir(), fs::path("/tmp/xdg/openphaco/meshes"));
  if (xdg) {
    ::setenv("XDG_CACHE_HOME", saved_xdg.c_str(), 1);
  } else {
    ::unsetenv("XDG_CACHE_HOME");
  }
  if (old) ::setenv("PHACO_CACHE_DIR", saved.c_str(), 1);
}

TEST(MeshCache, UnwritableDirectoryIsAnInputError) {
  MeshCache cache("/proc/phaco-cannot-write-here");
  EXPECT_THROW(cache.load_or_build(default_eye_params(), resolution_for_level(0),
                                   CapsuleLayout::Curvilinear, false),
               InputError);
}

}  // namespace
}  // namespace phaco::eye
