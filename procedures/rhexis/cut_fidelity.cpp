#include "procedures/rhexis/cut_fidelity.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace phaco::rhexis {
namespace {

double to_segment(const Vec3& x, const Vec3& a, const Vec3& b) {
  const Vec3 e = b - a;
  const double t =
      e.squaredNorm() > 0 ? std::clamp((x - a).dot(e) / e.squaredNorm(), 0.0, 1.0) : 0.0;
  return (x - (a + t * e)).norm();
}

}  // namespace

CutFidelity measure_cut_fidelity(const cut::CutMesh& m, std::span<const Vec3> path,
                                 double sample_mm) {
  CutFidelity f;
  if (path.size() < 2) return f;
  struct Lip {
    Vec3 a, b;
  };
  std::vector<Lip> lips;
  const Triangles& tr = m.triangles;
  for (uint32_t t = 0; t < tr.slots.size(); ++t) {
    if (!tr.slots.alive(t)) continue;
    for (int k = 0; k < 3; ++k) {
      if (m.topology.adjacency.neighbour[t][k] != kInvalidIndex) continue;
      const uint32_t u = cut::corner(tr, t, k), w = cut::corner(tr, t, (k + 1) % 3);
      if (m.particles.kind[u] == ParticleKind::Anchored &&
          m.particles.kind[w] == ParticleKind::Anchored)
        continue;
      lips.push_back(
          {cut::particle_position(m.particles, u), cut::particle_position(m.particles, w)});
    }
  }
  f.lip_edges = lips.size();
  if (lips.empty()) return f;
  for (const Lip& l : lips) {
    for (double s : {0.0, 0.5, 1.0}) {
      const Vec3 x = l.a + s * (l.b - l.a);
      double best = 1e300;
      for (size_t k = 0; k + 1 < path.size(); ++k)
        best = std::min(best, to_segment(x, path[k], path[k + 1]));
      f.cut_to_tool_mm = std::max(f.cut_to_tool_mm, best);
    }
  }
  for (size_t k = 0; k + 1 < path.size(); ++k) {
    const double len = (path[k + 1] - path[k]).norm();
    const int n = std::max(1, static_cast<int>(std::ceil(len / sample_mm)));
    for (int i = 0; i <= n; ++i) {
      const Vec3 x = path[k] + (path[k + 1] - path[k]) * (static_cast<double>(i) / n);
      double best = 1e300;
      for (const Lip& l : lips) best = std::min(best, to_segment(x, l.a, l.b));
      f.tool_to_cut_mm = std::max(f.tool_to_cut_mm, best);
    }
  }
  f.hausdorff_mm = std::max(f.cut_to_tool_mm, f.tool_to_cut_mm);
  return f;
}

}  // namespace phaco::rhexis
