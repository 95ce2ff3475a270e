#pragma once
// Inputs for the shape-matching measurements and micro-benchmarks (header-only, so the benchmark
// executables, which do not link phaco_perf_lens, build the same ones): seeded clouds and rigid
// transforms, and the lens split into fragments.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <vector>

#include "engine/core/math.hpp"
#include "engine/core/rng.hpp"
#include "procedures/eye/eye_mesh.hpp"
#include "procedures/eye/eye_params.hpp"
#include "procedures/eye/resolution.hpp"
#include "systems/sph/grid.hpp"

namespace phaco::perf::shape {

// Counter-based draws, one stream per generator.
class Gen {
 public:
  explicit Gen(uint64_t seed) : rng_(seed, 6) {}
  double uniform(double lo, double hi) { return lo + (hi - lo) * rng_.uniform_double(0, n_++); }
  Vec3 in_box(double h) { return {uniform(-h, h), uniform(-h, h), uniform(-h, h)}; }
  Quat rotation() {  // uniform on SO(3) (Shoemake)
    const double u1 = uniform(0, 1), u2 = uniform(0, 2 * M_PI), u3 = uniform(0, 2 * M_PI);
    const double a = std::sqrt(1 - u1), b = std::sqrt(u1);
    return Quat(a * std::sin(u2), a * std::cos(u2), b * std::sin(u3), b * std::cos(u3))
        .normalized();
  }

 private:
  CounterRng rng_;
  uint32_t n_ = 0;
};

// n cells in a 2 mm box (the size of a lens fragment).
inline std::vector<Vec3> box_cloud(Gen& g, int n) {
  std::vector<Vec3> p(n);
  for (auto& x : p) x = Vec3(0.5, -1, 1) + g.in_box(1.0);
  return p;
}

// n cells along a random 4 mm line, each up to `offset` mm off it.
inline std::vector<Vec3> line_cloud(Gen& g, int n, double offset) {
  const Quat r = g.rotation();
  std::vector<Vec3> p(n);
  for (auto& x : p)
    x = Vec3(0.5, -1, 1) +
        r * Vec3(g.uniform(-offset, offset), g.uniform(-offset, offset), g.uniform(-2, 2));
  return p;
}

// n cells on a random plane.
inline std::vector<Vec3> plane_cloud(Gen& g, int n) {
  const Quat r = g.rotation();
  std::vector<Vec3> p(n);
  for (auto& x : p) x = Vec3(0.5, -1, 1) + r * Vec3(g.uniform(-1, 1), g.uniform(-1, 1), 0);
  return p;
}

// The lens as cells: tet centres (float, as the hot per-cell state), tet volumes as masses, cut
// into `fragments` spatially compact fragments (cells sorted by a Morton key of their position,
// then split into equal runs; cell ids stay in tet order, so a fragment is gathered by index).
// Current positions: each fragment turned by up to 10° and moved, plus 0.01 mm of noise per cell.
struct LensFragments {
  std::vector<Vec3f> rest, current;
  std::vector<float> mass;
  std::vector<uint32_t> offsets, cells;
  std::vector<Quat> rotations;
};

inline LensFragments make_lens_fragments(int level, uint32_t fragments, uint64_t seed = 3) {
  const TetMesh mesh =
      eye::make_lens_tets(eye::default_eye_params(), eye::resolution_for_level(level));
  LensFragments l;
  const auto n = static_cast<uint32_t>(mesh.tets.size());
  l.rest.resize(n);
  l.mass.resize(n);
  std::vector<uint64_t> key(n);
  for (uint32_t t = 0; t < n; ++t) {
    const auto& tet = mesh.tets[t];
    const Vec3 &a = mesh.vertices[tet[0]], &b = mesh.vertices[tet[1]], &c = mesh.vertices[tet[2]],
               &d = mesh.vertices[tet[3]];
    const Vec3 centre = 0.25 * (a + b + c + d);
    l.rest[t] = centre.cast<float>();
    l.mass[t] = static_cast<float>((b - a).dot((c - a).cross(d - a)) / 6.0);
    auto q = [&](int axis) { return static_cast<uint32_t>((centre(axis) + 8.0) * 4096.0); };
    key[t] = sph::morton_key(q(0), q(1), q(2));
  }
  l.cells.resize(n);
  std::iota(l.cells.begin(), l.cells.end(), 0u);
  std::stable_sort(l.cells.begin(), l.cells.end(),
                   [&](uint32_t x, uint32_t y) { return key[x] < key[y]; });
  fragments = std::clamp<uint32_t>(fragments, 1, n);
  l.offsets.resize(fragments + 1);
  for (uint32_t f = 0; f <= fragments; ++f)
    l.offsets[f] = static_cast<uint32_t>(uint64_t{n} * f / fragments);
  Gen g(seed);
  l.current.resize(n);
  l.rotations.assign(fragments, Quat::Identity());
  for (uint32_t f = 0; f < fragments; ++f) {
    const Quat r(Eigen::AngleAxisd(g.uniform(0, 10 * M_PI / 180), g.rotation() * Vec3::UnitX()));
    const Vec3 t = g.in_box(0.2);
    for (uint32_t k = l.offsets[f]; k < l.offsets[f + 1]; ++k) {
      const uint32_t i = l.cells[k];
      l.current[i] = (r * l.rest[i].cast<double>() + t + g.in_box(0.01)).cast<float>();
    }
  }
  return l;
}

}  // namespace phaco::perf::shape
