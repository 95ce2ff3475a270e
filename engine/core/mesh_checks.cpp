#include "engine/core/mesh_checks.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "engine/core/error.hpp"

namespace phaco {
namespace {

// Union-find over dense indices; path halving keeps it short without recursion.
struct DisjointSets {
  std::vector<uint32_t> parent;
  explicit DisjointSets(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  uint32_t find(uint32_t x) {
    while (parent[x] != x) {
      parent[x] = parent[parent[x]];
      x = parent[x];
    }
    return x;
  }
  void unite(uint32_t a, uint32_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

struct DirectedEdge {
  uint64_t key;  // (min << 32) | max
  bool forward;  // traversed min -> max
};

uint64_t edge_key(uint32_t a, uint32_t b) {
  return (static_cast<uint64_t>(std::min(a, b)) << 32) | std::max(a, b);
}

}  // namespace

SurfaceTopology check_surface(const SurfaceMesh& mesh) {
  SurfaceTopology topo;
  const size_t nv = mesh.vertices.size();
  topo.vertices = nv;
  topo.triangles = mesh.triangles.size();

  std::vector<DirectedEdge> edges;
  edges.reserve(mesh.triangles.size() * 3);
  std::vector<uint32_t> use_count(nv, 0);
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    for (uint32_t v : tri) {
      if (v >= nv) {
        throw InputError("triangle " + std::to_string(t) + " refers to vertex " +
                         std::to_string(v) + " but the mesh has " + std::to_string(nv) +
                         " vertices");
      }
      ++use_count[v];
    }
    const Vec3& a = mesh.vertices[tri[0]];
    const Vec3& b = mesh.vertices[tri[1]];
    const Vec3& c = mesh.vertices[tri[2]];
    const double longest2 =
        std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
    const double area2 = (b - a).cross(c - a).norm();  // twice the area
    // Relative threshold: a sliver whose height is below 1e-9 of its longest edge is degenerate.
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] || area2 <= 1e-9 * longest2) {
      ++topo.degenerate_triangles;
    }
    for (int k = 0; k < 3; ++k) {
      const uint32_t u = tri[k];
      const uint32_t w = tri[(k + 1) % 3];
      if (u != w) edges.push_back({edge_key(u, w), u < w});
    }
  }
  topo.unreferenced_vertices =
      static_cast<size_t>(std::count(use_count.begin(), use_count.end(), 0u));

  std::sort(edges.begin(), edges.end(), [](const DirectedEdge& x, const DirectedEdge& y) {
    return x.key < y.key || (x.key == y.key && x.forward < y.forward);
  });
  DisjointSets boundary_sets(nv);
  std::vector<uint8_t> on_boundary(nv, 0);
  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    size_t forward = 0;
    while (j < edges.size() && edges[j].key == edges[i].key) forward += edges[j++].forward ? 1 : 0;
    const size_t uses = j - i;
    ++topo.edges;
    if (uses == 1) {
      ++topo.boundary_edges;
      const auto u = static_cast<uint32_t>(edges[i].key >> 32);
      const auto w = static_cast<uint32_t>(edges[i].key & 0xffffffffu);
      boundary_sets.unite(u, w);
      on_boundary[u] = on_boundary[w] = 1;
    } else if (uses > 2) {
      ++topo.nonmanifold_edges;
    } else if (forward != 1) {
      ++topo.inconsistent_edges;
    }
    i = j;
  }
  for (uint32_t v = 0; v < nv; ++v) {
    if (on_boundary[v] && boundary_sets.find(v) == v) ++topo.boundary_loops;
  }

  // Vertex manifoldness: the triangles around a vertex must be one fan, connected through the
  // edges that contain the vertex. Vertex -> triangle lists in compressed rows.
  std::vector<uint32_t> row(nv + 1, 0);
  for (size_t v = 0; v < nv; ++v) row[v + 1] = row[v] + use_count[v];
  std::vector<uint32_t> fill(row.begin(), row.end() - 1);
  std::vector<uint32_t> incident(row[nv]);
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (uint32_t v : mesh.triangles[t]) incident[fill[v]++] = static_cast<uint32_t>(t);
  }
  std::vector<std::pair<uint32_t, uint32_t>> spokes;  // (other vertex, local triangle)
  for (uint32_t v = 0; v < nv; ++v) {
    const uint32_t n = row[v + 1] - row[v];
    if (n < 2) continue;
    spokes.clear();
    for (uint32_t k = 0; k < n; ++k) {
      for (uint32_t w : mesh.triangles[incident[row[v] + k]]) {
        if (w != v) spokes.emplace_back(w, k);
      }
    }
    std::sort(spokes.begin(), spokes.end());
    DisjointSets fan(n);
    for (size_t i = 1; i < spokes.size(); ++i) {
      if (spokes[i].first == spokes[i - 1].first) fan.unite(spokes[i].second, spokes[i - 1].second);
    }
    uint32_t components = 0;
    for (uint32_t k = 0; k < n; ++k) components += fan.find(k) == k ? 1 : 0;
    if (components > 1) ++topo.nonmanifold_vertices;
  }
  return topo;
}

double signed_volume(const SurfaceMesh& mesh) {
  double sum = 0.0;
  for (const auto& tri : mesh.triangles) {
    const Vec3& a = mesh.vertices[tri[0]];
    const Vec3& b = mesh.vertices[tri[1]];
    const Vec3& c = mesh.vertices[tri[2]];
    sum += a.dot(b.cross(c));
  }
  return sum / 6.0;
}

double tet_signed_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return (b - a).dot((c - a).cross(d - a)) / 6.0;
}

double tet_radius_edge_ratio(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const Vec3 u = b - a;
  const Vec3 v = c - a;
  const Vec3 w = d - a;
  const double denom = 2.0 * u.dot(v.cross(w));
  if (denom == 0.0) return std::numeric_limits<double>::infinity();
  const Vec3 centre =
      (u.squaredNorm() * v.cross(w) + v.squaredNorm() * w.cross(u) + w.squaredNorm() * u.cross(v)) /
      denom;
  const double shortest2 =
      std::min({u.squaredNorm(), v.squaredNorm(), w.squaredNorm(), (c - b).squaredNorm(),
                (d - b).squaredNorm(), (d - c).squaredNorm()});
  return centre.norm() / std::sqrt(shortest2);
}

double tet_min_dihedral_deg(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  // Face normals, all outward (or all inward for an inverted tet; the angles are the same).
  const std::array<Vec3, 4> n = {(c - b).cross(d - b), (d - a).cross(c - a), (b - a).cross(d - a),
                                 (c - a).cross(b - a)};
  double smallest = 180.0;
  for (int i = 0; i < 4; ++i) {
    for (int j = i + 1; j < 4; ++j) {
      const double denom = n[i].norm() * n[j].norm();
      if (denom == 0.0) return 0.0;
      const double cosine = std::clamp(n[i].dot(n[j]) / denom, -1.0, 1.0);
      // Faces i and j meet at the edge opposite them; the dihedral is π minus the normals' angle.
      smallest = std::min(smallest, 180.0 - std::acos(cosine) * 180.0 / std::numbers::pi);
    }
  }
  return smallest;
}

TetQuality check_tets(const TetMesh& mesh) {
  TetQuality q;
  q.min_volume = mesh.tets.empty() ? 0.0 : std::numeric_limits<double>::infinity();
  q.min_dihedral_deg = mesh.tets.empty() ? 0.0 : 180.0;
  const size_t nv = mesh.vertices.size();
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    const auto& tet = mesh.tets[t];
    for (uint32_t v : tet) {
      if (v >= nv) {
        throw InputError("tet " + std::to_string(t) + " refers to vertex " + std::to_string(v) +
                         " but the mesh has " + std::to_string(nv) + " vertices");
      }
    }
    const Vec3& a = mesh.vertices[tet[0]];
    const Vec3& b = mesh.vertices[tet[1]];
    const Vec3& c = mesh.vertices[tet[2]];
    const Vec3& d = mesh.vertices[tet[3]];
    const double vol = tet_signed_volume(a, b, c, d);
    q.min_volume = std::min(q.min_volume, vol);
    q.total_volume += vol;
    if (vol <= 0.0) ++q.nonpositive;
    q.max_radius_edge = std::max(q.max_radius_edge, tet_radius_edge_ratio(a, b, c, d));
    q.min_dihedral_deg = std::min(q.min_dihedral_deg, tet_min_dihedral_deg(a, b, c, d));
  }
  return q;
}

}  // namespace phaco
