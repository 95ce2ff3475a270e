#pragma once
// Lens meshes (cached per level for the test process) and tip paths for the sculpting tests.
#include <map>
#include <vector>

#include "components/tet_topology.hpp"
#include "engine/core/rng.hpp"
#include "procedures/eye/eye_geometry.hpp"
#include "procedures/eye/eye_mesh.hpp"
#include "procedures/eye/eye_params.hpp"
#include "systems/sculpt/sculpt.hpp"
#include "systems/sculpt/swept_volume.hpp"

namespace phaco::sculpt::test {

inline const TetMesh& lens_tets(int level) {
  static std::map<int, TetMesh> cache;
  auto it = cache.find(level);
  if (it == cache.end())
    it = cache
             .emplace(level, eye::make_lens_tets(eye::default_eye_params(),
                                                 eye::resolution_for_level(level)))
             .first;
  return it->second;
}

inline LensShape lens_shape() {
  const eye::EyeGeometry g = eye::eye_geometry(eye::default_eye_params());
  return {g.lens_a, g.lens_c_anterior, g.lens_c_posterior};
}

// A random tip track: small steps in a random direction inside the lens's box, with an
// occasional jump (the tip leaves and comes back elsewhere) and a new power now and then.
inline std::vector<SculptTip> random_sweep(uint64_t seed, int steps) {
  const CounterRng rng(seed, 5);
  std::vector<SculptTip> track;
  Vec3 p(0.0, 0.0, 2.0);
  double radius = 0.45;
  for (int s = 0; s < steps; ++s) {
    auto u = [&](uint32_t draw) { return rng.uniform_double(static_cast<uint64_t>(s), 0, draw); };
    const Vec3 prev = p;
    if (u(0) < 0.04) {
      p = Vec3(-4.0 + 8.0 * u(1), -4.0 + 8.0 * u(2), -2.5 + 4.5 * u(3));
    } else {
      const Vec3 dir = Vec3(u(1) - 0.5, u(2) - 0.5, u(3) - 0.55).normalized();
      p += (0.02 + 0.2 * u(4)) * dir;
      p = p.cwiseMax(Vec3(-4.5, -4.5, -2.8)).cwiseMin(Vec3(4.5, 4.5, 2.2));
    }
    if (u(5) < 0.1) radius = sculpt_radius_mm(3.0, u(6));
    track.push_back({p, u(0) < 0.04 ? p : prev, radius});
  }
  return track;
}

// Tip samples along a polyline, every waypoint included, about `step_mm` apart.
inline std::vector<SculptTip> sample_path(const std::vector<Vec3>& path, double radius,
                                          double step_mm) {
  std::vector<SculptTip> track;
  track.push_back({path[0], path[0], radius});
  for (size_t i = 0; i + 1 < path.size(); ++i) {
    const int n =
        std::max(1, static_cast<int>(std::ceil((path[i + 1] - path[i]).norm() / step_mm)));
    for (int k = 1; k <= n; ++k) {
      const Vec3 p = path[i] + (path[i + 1] - path[i]) * (static_cast<double>(k) / n);
      track.push_back({p, track.back().centre, radius});
    }
  }
  return track;
}

}  // namespace phaco::sculpt::test
