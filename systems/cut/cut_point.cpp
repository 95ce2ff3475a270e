#include "systems/cut/cut_point.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace phaco::cut {
namespace {

struct Closest {
  Vec3 bary;  // weights of the corners
  Vec3 position;
  double distance = std::numeric_limits<double>::infinity();
};

// Closest point of triangle (A, B, C) to p by Voronoi regions (Ericson, Real-Time Collision
// Detection §5.1.5): exact barycentric zeros on edges and vertices, no division by a zero area.
Closest closest_on_triangle(const Vec3& p, const Vec3& A, const Vec3& B, const Vec3& C) {
  Closest r;
  const Vec3 ab = B - A, ac = C - A, ap = p - A;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) {
    r.bary = Vec3(1, 0, 0);
  } else {
    const Vec3 bp = p - B;
    const double d3 = ab.dot(bp), d4 = ac.dot(bp);
    const Vec3 cp = p - C;
    const double d5 = ab.dot(cp), d6 = ac.dot(cp);
    const double vc = d1 * d4 - d3 * d2;
    const double vb = d5 * d2 - d1 * d6;
    const double va = d3 * d6 - d5 * d4;
    if (d3 >= 0 && d4 <= d3) {
      r.bary = Vec3(0, 1, 0);
    } else if (d6 >= 0 && d5 <= d6) {
      r.bary = Vec3(0, 0, 1);
    } else if (vc <= 0 && d1 >= 0 && d3 <= 0) {
      const double v = d1 / (d1 - d3);
      r.bary = Vec3(1 - v, v, 0);
    } else if (vb <= 0 && d2 >= 0 && d6 <= 0) {
      const double w = d2 / (d2 - d6);
      r.bary = Vec3(1 - w, 0, w);
    } else if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
      const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
      r.bary = Vec3(0, 1 - w, w);
    } else {
      const double denom = va + vb + vc;
      if (!(denom > 0)) {  // degenerate triangle: nearest of its three edges
        r.bary = Vec3(1, 0, 0);
      } else {
        const double v = vb / denom, w = vc / denom;
        r.bary = Vec3(1 - v - w, v, w);
      }
    }
  }
  r.position = r.bary.x() * A + r.bary.y() * B + r.bary.z() * C;
  r.distance = (p - r.position).norm();
  return r;
}

Closest closest_on(const Particles& p, const Triangles& tr, uint32_t t, const Vec3& point) {
  return closest_on_triangle(point, particle_position(p, tr.a[t]), particle_position(p, tr.b[t]),
                             particle_position(p, tr.c[t]));
}

uint32_t scan_nearest(const Particles& p, const Triangles& tr, const Vec3& point) {
  uint32_t best = kInvalidIndex;
  double best_d = std::numeric_limits<double>::infinity();
  for (uint32_t t = 0; t < tr.slots.size(); ++t) {
    if (!tr.slots.alive(t)) continue;
    const double d = closest_on(p, tr, t, point).distance;
    if (d < best_d) best_d = d, best = t;
  }
  return best;
}

// Descends from `start` to a triangle whose closest point no neighbour (across an edge or around
// a vertex of that closest point) beats. Returns kInvalidIndex if the step budget runs out.
uint32_t walk(const Particles& p, const Triangles& tr, const TriangleAdjacency& adj, uint32_t start,
              const Vec3& point, std::vector<uint32_t>& fan) {
  uint32_t cur = start;
  Closest c = closest_on(p, tr, cur, point);
  const uint32_t budget = tr.slots.size() + 1;
  for (uint32_t step = 0; step < budget; ++step) {
    uint32_t next = kInvalidIndex;
    double next_d = c.distance;
    auto consider = [&](uint32_t n) {
      if (n == kInvalidIndex || n == cur) return;
      const double d =
          closest_on(p, tr, n, point).distance;  // strictly closer, lowest index on ties
      if (d < next_d || (d == next_d && next != kInvalidIndex && n < next)) next_d = d, next = n;
    };
    for (int k = 0; k < 3; ++k) {
      const bool on_vertex = c.bary[k] == 1.0;
      const bool on_edge = c.bary[(k + 2) % 3] == 0.0;  // edge k = (k, k+1) has weight 0 at k+2
      if (on_edge) consider(adj.neighbour[cur][k]);
      if (on_vertex) {
        vertex_fan(tr, adj, cur, corner(tr, cur, k), fan);
        for (uint32_t n : fan) consider(n);
      }
    }
    if (next == kInvalidIndex) return cur;
    cur = next;
    c = closest_on(p, tr, cur, point);
  }
  return kInvalidIndex;
}

void check_finite(const Vec3& v, const char* what) {
  if (!std::isfinite(v.x()) || !std::isfinite(v.y()) || !std::isfinite(v.z()))
    throw std::invalid_argument(std::string("cut: ") + what + " is not finite");
}

}  // namespace

TriangleAdjacency build_triangle_adjacency(const Triangles& tr, uint32_t particle_count) {
  const uint32_t n = tr.slots.size();
  TriangleAdjacency adj;
  adj.neighbour.assign(n, {kInvalidIndex, kInvalidIndex, kInvalidIndex});
  struct HalfEdge {
    uint64_t key;  // (min << 32) | max
    uint32_t tri;
    uint32_t k;
  };
  std::vector<HalfEdge> edges;
  edges.reserve(static_cast<size_t>(tr.slots.live_count()) * 3);
  for (uint32_t t = 0; t < n; ++t) {
    if (!tr.slots.alive(t)) continue;
    const uint32_t v[3] = {tr.a[t], tr.b[t], tr.c[t]};
    for (int k = 0; k < 3; ++k) {
      if (v[k] >= particle_count)
        throw std::invalid_argument("cut: triangle " + std::to_string(t) + " refers to particle " +
                                    std::to_string(v[k]) + " of " + std::to_string(particle_count));
    }
    if (v[0] == v[1] || v[1] == v[2] || v[2] == v[0])
      throw std::invalid_argument("cut: triangle " + std::to_string(t) + " repeats a vertex");
    for (uint32_t k = 0; k < 3; ++k) {
      const uint64_t lo = std::min(v[k], v[(k + 1) % 3]), hi = std::max(v[k], v[(k + 1) % 3]);
      edges.push_back({(lo << 32) | hi, t, k});
    }
  }
  std::sort(edges.begin(), edges.end(), [](const HalfEdge& l, const HalfEdge& r) {
    return l.key != r.key ? l.key < r.key : l.tri < r.tri;
  });
  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    while (j < edges.size() && edges[j].key == edges[i].key) ++j;
    if (j - i == 2) {
      adj.neighbour[edges[i].tri][edges[i].k] = edges[i + 1].tri;
      adj.neighbour[edges[i + 1].tri][edges[i + 1].k] = edges[i].tri;
    }
    i = j;
  }
  return adj;
}

void vertex_fan(const Triangles& tr, const TriangleAdjacency& adj, uint32_t triangle,
                uint32_t vertex, std::vector<uint32_t>& out) {
  out.clear();
  out.push_back(triangle);
  // Turn one way across the edge after the vertex, then (if the fan is open) the other way.
  for (int dir = 0; dir < 2; ++dir) {
    uint32_t cur = triangle;
    for (uint32_t guard = 0; guard < adj.neighbour.size(); ++guard) {
      const int k = corner_slot(tr, cur, vertex);
      const int edge = dir == 0 ? k : (k + 2) % 3;  // edge (k, k+1) or (k-1, k)
      const uint32_t n = adj.neighbour[cur][edge];
      if (n == kInvalidIndex || n == triangle) break;
      if (std::find(out.begin(), out.end(), n) != out.end()) break;
      out.push_back(n);
      cur = n;
    }
  }
  std::sort(out.begin(), out.end());
}

CutPoint locate_cut_point(const Particles& p, const Triangles& tr, const TriangleAdjacency& adj,
                          uint32_t start_triangle, const Vec3& point, const SnapSettings& snap) {
  check_finite(point, "cut point");
  if (!(snap.vertex_snap_mm >= 0) || !(snap.edge_snap_mm >= 0) ||
      !std::isfinite(snap.vertex_snap_mm) || !std::isfinite(snap.edge_snap_mm))
    throw std::invalid_argument("cut: snap thresholds must be finite and >= 0");
  if (adj.neighbour.size() != tr.slots.size())
    throw std::invalid_argument("cut: adjacency built for another triangle table (rebuild it)");
  if (tr.slots.live_count() == 0) throw std::invalid_argument("cut: mesh has no live triangle");

  std::vector<uint32_t> fan;
  fan.reserve(16);
  uint32_t t = kInvalidIndex;
  if (tr.slots.alive(start_triangle)) t = walk(p, tr, adj, start_triangle, point, fan);
  if (t == kInvalidIndex) t = scan_nearest(p, tr, point);

  const Closest c = closest_on(p, tr, t, point);
  check_finite(c.position, "mesh position near the cut point");
  CutPoint r;

  // Vertex snap first (seed order), then edge snap; nearest feature wins within each.
  int best_v = 0;
  double best_vd = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    const double d = (c.position - particle_position(p, corner(tr, t, k))).norm();
    if (d < best_vd) best_vd = d, best_v = k;
  }
  if (c.bary[best_v] != 1.0 && best_vd > snap.vertex_snap_mm) best_v = -1;
  if (best_v >= 0) {
    const uint32_t v = corner(tr, t, best_v);
    vertex_fan(tr, adj, t, v, fan);
    r.kind = CutPoint::Vertex;
    r.triangle = fan.front();
    r.a = v;
    r.position = particle_position(p, v);
    r.bary = Vec3::Zero();
    r.bary[corner_slot(tr, r.triangle, v)] = 1.0;
    r.distance_mm = (point - r.position).norm();
    return r;
  }

  int best_e = -1;
  double best_t = 0.0, best_ed = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    const Vec3 x0 = particle_position(p, corner(tr, t, k));
    const Vec3 x1 = particle_position(p, corner(tr, t, (k + 1) % 3));
    const Vec3 e = x1 - x0;
    const double len2 = e.squaredNorm();
    const double s = len2 > 0 ? std::clamp((c.position - x0).dot(e) / len2, 0.0, 1.0) : 0.0;
    const double d = (c.position - (x0 + s * e)).norm();
    const bool exact = c.bary[(k + 2) % 3] == 0.0;
    if ((exact || d <= snap.edge_snap_mm) && (best_e < 0 || d < best_ed)) {
      best_e = k, best_t = s, best_ed = d;
    }
  }
  if (best_e >= 0) {
    uint32_t a = corner(tr, t, best_e), b = corner(tr, t, (best_e + 1) % 3);
    double s = best_t;
    if (a > b) std::swap(a, b), s = 1.0 - s;
    const uint32_t other = adj.neighbour[t][best_e];
    r.kind = CutPoint::Edge;
    r.triangle = other != kInvalidIndex ? std::min(t, other) : t;
    r.a = a;
    r.b = b;
    r.t = s;
    r.position = (1.0 - s) * particle_position(p, a) + s * particle_position(p, b);
    r.bary = Vec3::Zero();
    r.bary[corner_slot(tr, r.triangle, a)] = 1.0 - s;
    r.bary[corner_slot(tr, r.triangle, b)] = s;
    r.distance_mm = (point - r.position).norm();
    return r;
  }

  r.kind = CutPoint::Face;
  r.triangle = t;
  r.bary = c.bary;
  r.position = c.position;
  r.distance_mm = c.distance;
  return r;
}

bool projected_bary(const Particles& p, const Triangles& tr, uint32_t T, const Vec3& q, Vec3& w) {
  const Vec3 A = particle_position(p, tr.a[T]);
  const Vec3 v0 = particle_position(p, tr.b[T]) - A, v1 = particle_position(p, tr.c[T]) - A;
  const Vec3 v2 = q - A;
  const double d00 = v0.dot(v0), d01 = v0.dot(v1), d11 = v1.dot(v1);
  const double d20 = v2.dot(v0), d21 = v2.dot(v1);
  const double denom = d00 * d11 - d01 * d01;
  if (!(denom > 1e-300)) return false;
  const double v = (d11 * d20 - d01 * d21) / denom, u = (d00 * d21 - d01 * d20) / denom;
  w = Vec3(1.0 - v - u, v, u);
  return true;
}

double exit_parameter(const Vec3& from, const Vec3& target, int& exit) {
  constexpr double kDirTol = 1e-12;  // barycentric rate treated as zero (moving along an edge)
  const Vec3 d = target - from;
  double s = std::numeric_limits<double>::infinity();
  exit = -1;
  for (int i = 0; i < 3; ++i) {
    if (d[i] >= -kDirTol) continue;
    const double si = std::max(from[i], 0.0) / -d[i];
    if (si < s) s = si, exit = i;
  }
  return s;
}

TriangleGrid build_triangle_grid(const Particles& p, const Triangles& tr) {
  TriangleGrid g;
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  double edge_sum = 0.0;
  uint32_t live = 0;
  for (uint32_t t = 0; t < tr.slots.size(); ++t) {
    if (!tr.slots.alive(t)) continue;
    const Vec3 a = particle_position(p, tr.a[t]), b = particle_position(p, tr.b[t]),
               c = particle_position(p, tr.c[t]);
    lo = lo.cwiseMin(a).cwiseMin(b).cwiseMin(c), hi = hi.cwiseMax(a).cwiseMax(b).cwiseMax(c);
    edge_sum += (b - a).norm() + (c - b).norm() + (a - c).norm();
    ++live;
  }
  if (live == 0) return g;
  g.cell_mm = std::max(2.0 * edge_sum / (3.0 * live), 1e-6);
  g.origin = lo;
  for (int k = 0; k < 3; ++k)
    g.dims[k] =
        static_cast<uint32_t>(std::min(1024.0, std::floor((hi[k] - lo[k]) / g.cell_mm) + 1.0));
  const auto cell_of = [&](const Vec3& x) {
    uint32_t c[3];
    for (int k = 0; k < 3; ++k)
      c[k] = static_cast<uint32_t>(
          std::clamp((x[k] - g.origin[k]) / g.cell_mm, 0.0, double(g.dims[k] - 1)));
    return (size_t{c[2]} * g.dims[1] + c[1]) * g.dims[0] + c[0];
  };
  const size_t cells = size_t{g.dims[0]} * g.dims[1] * g.dims[2];
  g.cell_begin.assign(cells + 1, 0);
  std::vector<size_t> cell(tr.slots.size(), cells);
  for (uint32_t t = 0; t < tr.slots.size(); ++t) {
    if (!tr.slots.alive(t)) continue;
    cell[t] = cell_of((particle_position(p, tr.a[t]) + particle_position(p, tr.b[t]) +
                       particle_position(p, tr.c[t])) /
                      3.0);
    ++g.cell_begin[cell[t] + 1];
  }
  for (size_t c = 0; c < cells; ++c) g.cell_begin[c + 1] += g.cell_begin[c];
  g.triangles.resize(g.cell_begin.back());
  std::vector<uint32_t> fill(g.cell_begin.begin(), g.cell_begin.end() - 1);
  for (uint32_t t = 0; t < tr.slots.size(); ++t)  // in index order: each cell's list is sorted
    if (cell[t] < cells) g.triangles[fill[cell[t]]++] = t;
  return g;
}

uint32_t nearest_binned_triangle(const TriangleGrid& g, const Particles& p, const Triangles& tr,
                                 const Vec3& point) {
  if (g.cell_begin.empty()) return kInvalidIndex;
  int c[3];
  for (int k = 0; k < 3; ++k) {
    const double f = std::floor((point[k] - g.origin[k]) / g.cell_mm);
    if (f < -1.0 || f > double(g.dims[k])) return kInvalidIndex;
    c[k] = static_cast<int>(f);
  }
  uint32_t best = kInvalidIndex;
  double best_d = std::numeric_limits<double>::infinity();
  for (int z = c[2] - 1; z <= c[2] + 1; ++z)
    for (int y = c[1] - 1; y <= c[1] + 1; ++y)
      for (int x = c[0] - 1; x <= c[0] + 1; ++x) {
        if (x < 0 || y < 0 || z < 0 || x >= int(g.dims[0]) || y >= int(g.dims[1]) ||
            z >= int(g.dims[2]))
          continue;
        const size_t cell = (size_t(z) * g.dims[1] + size_t(y)) * g.dims[0] + size_t(x);
        for (uint32_t k = g.cell_begin[cell]; k < g.cell_begin[cell + 1]; ++k) {
          const uint32_t t = g.triangles[k];
          if (!tr.slots.alive(t)) continue;
          const double d = closest_on(p, tr, t, point).distance;
          if (d < best_d || (d == best_d && t < best)) best_d = d, best = t;
        }
      }
  return best;
}

}  // namespace phaco::cut
