#include "procedures/incision/cut_measure.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace phaco::corneal_incision {
namespace {

Vec3 centre_of(const incision::CorneaSpheres& s, Surface surface) {
  return {0.0, 0.0, surface == Surface::Anterior ? s.anterior_centre_z : s.posterior_centre_z};
}

double radius_of(const incision::CorneaSpheres& s, Surface surface) {
  return surface == Surface::Anterior ? s.anterior_radius_mm : s.posterior_radius_mm;
}

Surface other(Surface s) {
  return s == Surface::Anterior ? Surface::Posterior : Surface::Anterior;
}

double point_segment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 e = b - a;
  const double l2 = e.squaredNorm();
  const double t = l2 > 0.0 ? std::clamp((p - a).dot(e) / l2, 0.0, 1.0) : 0.0;
  return (p - (a + t * e)).norm();
}

// max over samples of segments `a` of the distance to the nearest segment of `b`.
double directed(const std::vector<std::array<Vec3, 2>>& a,
                const std::vector<std::array<Vec3, 2>>& b, double sample_mm) {
  if (a.empty() || b.empty()) return 0.0;
  double worst = 0.0;
  for (const auto& s : a) {
    const int n = std::max(1, static_cast<int>(std::ceil((s[1] - s[0]).norm() / sample_mm)));
    for (int k = 0; k <= n; ++k) {
      const Vec3 p = s[0] + (static_cast<double>(k) / n) * (s[1] - s[0]);
      double best = std::numeric_limits<double>::infinity();
      for (const auto& t : b) best = std::min(best, point_segment(p, t[0], t[1]));
      worst = std::max(worst, best);
    }
  }
  return worst;
}

// The distinct vertices of the lip edges, sorted.
std::vector<uint32_t> lip_vertices(const std::vector<std::array<uint32_t, 2>>& edges) {
  std::vector<uint32_t> v;
  for (const auto& e : edges) v.push_back(e[0]), v.push_back(e[1]);
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
  return v;
}

// Connected pieces of the lip edges (union–find over their vertices) and whether every vertex has
// exactly two of them. A slit's edge, listed once from each side, counts twice: its two crack
// tips then have degree two as well, and the slit is a loop of two edges.
void lip_graph(const std::vector<std::array<uint32_t, 2>>& edges, SurfaceCut& out) {
  const std::vector<uint32_t> verts = lip_vertices(edges);
  const auto index = [&](uint32_t v) {
    return static_cast<uint32_t>(std::lower_bound(verts.begin(), verts.end(), v) - verts.begin());
  };
  std::vector<uint32_t> parent(verts.size()), degree(verts.size(), 0);
  for (uint32_t i = 0; i < parent.size(); ++i) parent[i] = i;
  const auto root = [&](uint32_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (const auto& e : edges) {
    const uint32_t a = index(e[0]), b = index(e[1]);
    ++degree[a], ++degree[b];
    parent[root(a)] = root(b);
  }
  out.lip_loops = 0;
  out.lips_closed = !verts.empty();
  for (uint32_t i = 0; i < verts.size(); ++i) {
    if (root(i) == i) ++out.lip_loops;
    if (degree[i] != 2) out.lips_closed = false;
  }
}

}  // namespace

double sphere_offset(const incision::CorneaSpheres& s, Surface surface, const Vec3& p) {
  return std::abs((p - centre_of(s, surface)).norm() - radius_of(s, surface));
}

void lip_edges(const cut::CutMesh& m, const incision::CorneaSpheres& s, Surface surface,
               std::vector<std::array<uint32_t, 2>>& out) {
  out.clear();
  const auto& adj = m.topology.adjacency.neighbour;
  for (uint32_t t = 0; t < m.triangles.slots.size(); ++t) {
    if (!m.triangles.slots.alive(t)) continue;
    for (int k = 0; k < 3; ++k) {
      if (adj[t][k] != kInvalidIndex) continue;
      const uint32_t a = cut::corner(m.triangles, t, k),
                     b = cut::corner(m.triangles, t, (k + 1) % 3);
      const Vec3 mid =
          0.5 * (cut::particle_position(m.particles, a) + cut::particle_position(m.particles, b));
      if (sphere_offset(s, surface, mid) <= sphere_offset(s, other(surface), mid))
        out.push_back({a, b});
    }
  }
}

Hausdorff segment_hausdorff(const std::vector<std::array<Vec3, 2>>& a,
                            const std::vector<std::array<Vec3, 2>>& b, double sample_mm) {
  if (!std::isfinite(sample_mm) || !(sample_mm > 0.0))
    throw std::invalid_argument("segment_hausdorff: sample_mm must be finite and > 0");
  Hausdorff h;
  h.a_to_b = directed(a, b, sample_mm);
  h.b_to_a = directed(b, a, sample_mm);
  h.both = std::max(h.a_to_b, h.b_to_a);
  return h;
}

SurfaceCut measure_surface_cut(const cut::CutMesh& m, const incision::CorneaSpheres& s,
                               Surface surface, uint32_t left_tip, uint32_t right_tip,
                               const std::vector<Vec3>& tool_points, double sample_mm) {
  if (!std::isfinite(sample_mm) || !(sample_mm > 0.0))
    throw std::invalid_argument("measure_surface_cut: sample_mm must be finite and > 0");
  SurfaceCut out;
  std::vector<std::array<uint32_t, 2>> edges;
  lip_edges(m, s, surface, edges);
  out.lip_edges = static_cast<uint32_t>(edges.size());
  const auto& P = m.particles;
  const bool tips = P.slots.alive(left_tip) && P.slots.alive(right_tip);
  out.exists = !edges.empty() && tips;
  if (edges.empty()) return out;

  std::vector<std::array<Vec3, 2>> lips, tool;
  double total = 0.0;
  out.min_other_surface_mm = std::numeric_limits<double>::infinity();
  for (const auto& e : edges) {
    const Vec3 a = cut::particle_position(P, e[0]), b = cut::particle_position(P, e[1]);
    lips.push_back({a, b});
    total += (b - a).norm();
    for (const Vec3& v : {a, b}) {
      out.max_surface_offset_mm = std::max(out.max_surface_offset_mm, sphere_offset(s, surface, v));
      out.min_other_surface_mm =
          std::min(out.min_other_surface_mm, sphere_offset(s, other(surface), v));
      const double r = std::hypot(v.x(), v.y());
      out.max_radius_mm = std::max(out.max_radius_mm, r);
    }
  }
  lip_graph(edges, out);
  for (uint32_t v : lip_vertices(edges))
    if (std::hypot(P.x[v], P.y[v]) >= s.limbus_radius_mm - 1e-6) ++out.rim_vertices;
  out.lip_length_mm = 0.5 * total;

  for (size_t k = 1; k < tool_points.size(); ++k)
    tool.push_back({tool_points[k - 1], tool_points[k]});
  if (tool.empty() && !tool_points.empty()) tool.push_back({tool_points[0], tool_points[0]});
  const Hausdorff h = segment_hausdorff(lips, tool, sample_mm);
  out.lips_to_tool_mm = h.a_to_b;
  out.tool_to_lips_mm = h.b_to_a;
  out.hausdorff_mm = h.both;

  if (!tips) return out;
  out.left_end = cut::particle_position(P, left_tip);
  out.right_end = cut::particle_position(P, right_tip);
  out.chord_mm = (out.right_end - out.left_end).norm();
  if (!(out.chord_mm > 0.0)) return out;
  // The middle: where the lips cross the plane bisecting the two tips (one crossing per lip).
  const Vec3 u = (out.right_end - out.left_end) / out.chord_mm;
  const Vec3 c = 0.5 * (out.left_end + out.right_end);
  Vec3 sum = Vec3::Zero();
  int n = 0;
  for (const auto& l : lips) {
    const double da = (l[0] - c).dot(u), db = (l[1] - c).dot(u);
    if ((da < 0.0) == (db < 0.0) || da == db) continue;
    sum += l[0] + (da / (da - db)) * (l[1] - l[0]);
    ++n;
  }
  if (n > 0) out.middle = sum / n;
  return out;
}

}  // namespace phaco::corneal_incision
