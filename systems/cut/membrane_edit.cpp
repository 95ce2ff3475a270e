#include "systems/cut/membrane_edit.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <stdexcept>
#include <string>

#include "engine/core/invariants.hpp"

namespace phaco::cut {
namespace {

constexpr double kPi = 3.14159265358979323846;

void ensure_sizes(CutMesh& m) {
  MembraneTopology& g = m.topology;
  const size_t nt = m.triangles.slots.size(), np = m.particles.slots.size();
  if (g.adjacency.neighbour.size() < nt)
    g.adjacency.neighbour.resize(nt, {kInvalidIndex, kInvalidIndex, kInvalidIndex});
  if (g.vertex_triangle.size() < np) {
    g.vertex_triangle.resize(np, kInvalidIndex);
    g.rest_x.resize(np, 0.0);
    g.rest_y.resize(np, 0.0);
    g.rest_z.resize(np, 0.0);
  }
}

// Edge slot k of triangle t (corners k, k+1) joining u and v in either direction; -1 if none.
int edge_slot(const Triangles& tr, uint32_t t, uint32_t u, uint32_t v) {
  for (int k = 0; k < 3; ++k) {
    const uint32_t c0 = corner(tr, t, k), c1 = corner(tr, t, (k + 1) % 3);
    if ((c0 == u && c1 == v) || (c0 == v && c1 == u)) return k;
  }
  return -1;
}

void set_corner(Triangles& tr, uint32_t t, int k, uint32_t v) {
  (k == 0 ? tr.a : (k == 1 ? tr.b : tr.c))[t] = v;
}

void set_link(CutMesh& m, uint32_t t, uint32_t u, uint32_t v, uint32_t n) {
  if (t == kInvalidIndex) return;
  const int k = edge_slot(m.triangles, t, u, v);
  if (k >= 0) m.topology.adjacency.neighbour[t][k] = n;
}

uint32_t link_across(const CutMesh& m, uint32_t t, uint32_t u, uint32_t v) {
  const int k = edge_slot(m.triangles, t, u, v);
  return k >= 0 ? m.topology.adjacency.neighbour[t][k] : kInvalidIndex;
}

uint32_t add_triangle(CutMesh& m, uint32_t a, uint32_t b, uint32_t c) {
  const uint32_t t = table_add(m.triangles);
  m.triangles.a[t] = a;
  m.triangles.b[t] = b;
  m.triangles.c[t] = c;
  ensure_sizes(m);
  m.topology.adjacency.neighbour[t] = {kInvalidIndex, kInvalidIndex, kInvalidIndex};
  return t;
}

// A new particle: a copy of `from`'s state, or (when w > 0) the blend (1-w)·from + w·other.
uint32_t add_particle(CutMesh& m, uint32_t from, uint32_t other, double w) {
  Particles& p = m.particles;
  const uint32_t v = table_add(p);
  ensure_sizes(m);
  MembraneTopology& g = m.topology;
  const auto mix = [&](auto& col) {
    using T = std::decay_t<decltype(col[0])>;
    col[v] =
        other == kInvalidIndex ? col[from] : static_cast<T>((1.0 - w) * col[from] + w * col[other]);
  };
  mix(p.x), mix(p.y), mix(p.z), mix(p.vx), mix(p.vy), mix(p.vz), mix(p.inv_mass);
  mix(g.rest_x), mix(g.rest_y), mix(g.rest_z);
  if (other == kInvalidIndex) {
    p.kind[v] = p.kind[from];
  } else {
    const bool anchored =
        p.kind[from] == ParticleKind::Anchored && p.kind[other] == ParticleKind::Anchored;
    p.kind[v] = anchored ? ParticleKind::Anchored : ParticleKind::Free;
    if (!anchored && p.inv_mass[v] == 0.0f)
      p.inv_mass[v] = std::max(p.inv_mass[from], p.inv_mass[other]);
    if (anchored) p.inv_mass[v] = 0.0f;
  }
  g.vertex_triangle[v] = kInvalidIndex;
  return v;
}

void add_spring(CutMesh& m, uint32_t a, uint32_t b) {
  const uint64_t key = edge_key(a, b);
  if (m.topology.spring_of_edge.count(key)) return;
  const uint32_t s = table_append(m.springs, 1);  // never a freed slot: see MembraneTopology
  m.springs.i[s] = std::min(a, b);
  m.springs.j[s] = std::max(a, b);
  // Provisional: refresh_region sets both from the rest shape.
  const Vec3 d = rest_position(m.topology, a) - rest_position(m.topology, b);
  m.springs.rest_length[s] = static_cast<float>((1.0 - m.material.springs.prestretch) * d.norm());
  m.springs.stiffness[s] = 0.0f;
  m.topology.spring_of_edge.emplace(key, s);
  m.topology.added_springs.push_back(s);
}

void remove_spring(CutMesh& m, uint32_t a, uint32_t b) {
  const auto it = m.topology.spring_of_edge.find(edge_key(a, b));
  if (it == m.topology.spring_of_edge.end()) return;
  table_remove(m.springs, it->second);
  m.springs.stiffness[it->second] = 0.0f;  // a tombstone pulls nothing in passes that skip no slot
  m.topology.removed_springs.push_back(it->second);
  m.topology.spring_of_edge.erase(it);
}

double rest_area(const CutMesh& m, uint32_t t) {
  const Vec3 a = rest_position(m.topology, m.triangles.a[t]),
             b = rest_position(m.topology, m.triangles.b[t]),
             c = rest_position(m.topology, m.triangles.c[t]);
  return 0.5 * (b - a).cross(c - a).norm();
}

void push_unique(std::vector<uint32_t>& v, uint32_t x) {
  if (std::find(v.begin(), v.end(), x) == v.end()) v.push_back(x);
}

// Neighbours of v over the given triangles (the corners that are not v).
void neighbours_over(const Triangles& tr, const std::vector<uint32_t>& tris, uint32_t v,
                     std::vector<uint32_t>& out) {
  out.clear();
  for (uint32_t t : tris) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t c = corner(tr, t, k);
      if (c != v) push_unique(out, c);
    }
  }
}

// Gives every connected component of v's triangles (found from the candidates) but the first its
// own copy of v, moving or splitting v's springs to match.
void separate_wedges(CutMesh& m, uint32_t v, const std::vector<uint32_t>& candidates,
                     EditLog& log) {
  std::vector<std::vector<uint32_t>> components;
  std::vector<uint32_t> fan;
  for (uint32_t c : candidates) {
    if (!m.triangles.slots.alive(c) || corner_slot(m.triangles, c, v) < 0) continue;
    bool seen = false;
    for (const auto& comp : components)
      seen = seen || std::find(comp.begin(), comp.end(), c) != comp.end();
    if (seen) continue;
    vertex_fan(m.triangles, m.topology.adjacency, c, v, fan);
    components.push_back(fan);
  }
  if (components.empty()) return;
  m.topology.vertex_triangle[v] = components[0][0];
  for (uint32_t t : components[0]) log.touched_triangles.push_back(t);
  std::vector<uint32_t> moved, kept, still;
  for (size_t i = 1; i < components.size(); ++i) {
    const uint32_t copy = add_particle(m, v, kInvalidIndex, 0.0);
    neighbours_over(m.triangles, components[i], v, moved);
    for (uint32_t t : components[i])
      set_corner(m.triangles, t, corner_slot(m.triangles, t, v), copy);
    still.clear();
    for (size_t j = 0; j < components.size(); ++j)
      if (j == 0 || j > i) still.insert(still.end(), components[j].begin(), components[j].end());
    neighbours_over(m.triangles, still, v, kept);
    for (uint32_t n : moved) {
      if (std::find(kept.begin(), kept.end(), n) == kept.end()) remove_spring(m, v, n);
      add_spring(m, copy, n);
    }
    m.topology.vertex_triangle[copy] = components[i][0];
    for (uint32_t t : components[i]) log.touched_triangles.push_back(t);
    log.new_particles.push_back(copy);
    log.origins.push_back({copy, {v, kInvalidIndex, kInvalidIndex}, {1.0, 0.0, 0.0}});
    ++log.duplicated_vertices;
  }
}

double angle_deg(const Vec3& u, const Vec3& w) {
  const double c = u.normalized().dot(w.normalized());
  return std::acos(std::clamp(c, -1.0, 1.0)) * 180.0 / kPi;
}

}  // namespace

// Shared with the other edit files of this folder (systems/cut/edit_detail.hpp).
namespace detail {
int edge_slot(const Triangles& tr, uint32_t t, uint32_t u, uint32_t v) {
  return cut::edge_slot(tr, t, u, v);
}
void set_link(CutMesh& m, uint32_t t, uint32_t u, uint32_t v, uint32_t n) {
  cut::set_link(m, t, u, v, n);
}
uint32_t link_across(const CutMesh& m, uint32_t t, uint32_t u, uint32_t v) {
  return cut::link_across(m, t, u, v);
}
void add_spring(CutMesh& m, uint32_t a, uint32_t b) {
  cut::add_spring(m, a, b);
}
void remove_spring(CutMesh& m, uint32_t a, uint32_t b) {
  cut::remove_spring(m, a, b);
}
void push_unique(std::vector<uint32_t>& v, uint32_t x) {
  cut::push_unique(v, x);
}
}  // namespace detail

void EditLog::clear() {
  *this = EditLog{};
}

Vec3 rest_position(const MembraneTopology& g, uint32_t v) {
  return {g.rest_x[v], g.rest_y[v], g.rest_z[v]};
}

double min_angle_deg(const Vec3& p0, const Vec3& p1, const Vec3& p2) {
  const Vec3 e01 = p1 - p0, e12 = p2 - p1, e20 = p0 - p2;
  if (e01.norm() == 0 || e12.norm() == 0 || e20.norm() == 0) return 0.0;
  const double a0 = angle_deg(e01, -e20), a1 = angle_deg(e12, -e01);
  const double a2 = 180.0 - a0 - a1;
  return std::min({a0, a1, a2});
}

MembraneTopology build_topology(const Particles& p, const Triangles& tr, const Springs& s) {
  MembraneTopology g;
  const uint32_t np = p.slots.size();
  g.adjacency = build_triangle_adjacency(tr, np);
  g.vertex_triangle.assign(np, kInvalidIndex);
  g.rest_x.assign(p.x.begin(), p.x.end());
  g.rest_y.assign(p.y.begin(), p.y.end());
  g.rest_z.assign(p.z.begin(), p.z.end());
  for (uint32_t e = 0; e < s.slots.size(); ++e) {
    if (!s.slots.alive(e)) continue;
    if (!g.spring_of_edge.emplace(edge_key(s.i[e], s.j[e]), e).second)
      throw std::invalid_argument("cut: springs " + std::to_string(e) + " and " +
                                  std::to_string(g.spring_of_edge[edge_key(s.i[e], s.j[e])]) +
                                  " join the same particles");
  }
  for (uint32_t t = 0; t < tr.slots.size(); ++t) {
    if (!tr.slots.alive(t)) continue;
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = corner(tr, t, k), w = corner(tr, t, (k + 1) % 3);
      if (g.vertex_triangle[v] == kInvalidIndex) g.vertex_triangle[v] = t;
      if (!g.spring_of_edge.count(edge_key(v, w)))
        throw std::invalid_argument("cut: edge (" + std::to_string(v) + ", " + std::to_string(w) +
                                    ") of triangle " + std::to_string(t) + " has no spring");
    }
  }
  return g;
}

void reserve_for_cuts(CutMesh& m, uint32_t extra) {
  const size_t np = m.particles.slots.size() + extra,
               nt = m.triangles.slots.size() + 2 * size_t{extra},
               ns = m.springs.slots.size() + 3 * size_t{extra};
  m.particles.slots.reserve(static_cast<uint32_t>(np));
  m.triangles.slots.reserve(static_cast<uint32_t>(nt));
  m.springs.slots.reserve(static_cast<uint32_t>(ns));
  m.particles.for_each_column([&](auto& col) { col.reserve(np); });
  m.triangles.for_each_column([&](auto& col) { col.reserve(nt); });
  m.springs.for_each_column([&](auto& col) { col.reserve(ns); });
  MembraneTopology& g = m.topology;
  g.adjacency.neighbour.reserve(nt);
  g.vertex_triangle.reserve(np);
  g.rest_x.reserve(np), g.rest_y.reserve(np), g.rest_z.reserve(np);
  g.spring_of_edge.reserve(ns);
  g.added_springs.reserve(3 * size_t{extra});
  g.removed_springs.reserve(3 * size_t{extra});
}

void triangles_on_edge(const CutMesh& m, uint32_t a, uint32_t b, std::vector<uint32_t>& out) {
  out.clear();
  if (!m.particles.slots.alive(a) || a >= m.topology.vertex_triangle.size()) return;
  const uint32_t h = m.topology.vertex_triangle[a];
  if (!m.triangles.slots.alive(h)) return;
  std::vector<uint32_t> fan;
  vertex_fan(m.triangles, m.topology.adjacency, h, a, fan);
  for (uint32_t t : fan)
    if (corner_slot(m.triangles, t, b) >= 0) out.push_back(t);
}

bool joined_edge(const CutMesh& m, uint32_t a, uint32_t b) {
  std::vector<uint32_t> tris;
  triangles_on_edge(m, a, b, tris);
  return tris.size() == 2 && link_across(m, tris[0], a, b) == tris[1];
}

bool on_boundary(const CutMesh& m, uint32_t v) {
  const uint32_t h = m.topology.vertex_triangle[v];
  if (!m.triangles.slots.alive(h)) return false;
  std::vector<uint32_t> fan;
  vertex_fan(m.triangles, m.topology.adjacency, h, v, fan);
  for (uint32_t t : fan) {
    const int k = corner_slot(m.triangles, t, v);
    if (m.topology.adjacency.neighbour[t][k] == kInvalidIndex ||
        m.topology.adjacency.neighbour[t][(k + 2) % 3] == kInvalidIndex)
      return true;
  }
  return false;
}

uint32_t split_edge(CutMesh& m, uint32_t a, uint32_t b, double t, EditLog& log) {
  std::vector<uint32_t> tris;
  triangles_on_edge(m, a, b, tris);
  if (tris.empty() || !(t > 0.0 && t < 1.0))
    throw std::invalid_argument("split_edge: (" + std::to_string(a) + ", " + std::to_string(b) +
                                ") is not an edge or t is not in (0, 1)");
  // Which of the edge's triangles were neighbours across it (not a slit).
  const bool linked = tris.size() == 2 && link_across(m, tris[0], a, b) == tris[1];
  const uint32_t q = add_particle(m, a, b, t);
  struct Piece {
    uint32_t with_a, with_b;
  };
  std::vector<Piece> pieces;
  std::vector<uint32_t> all;
  for (uint32_t T : tris) {
    const int k = edge_slot(m.triangles, T, a, b);
    const uint32_t u = corner(m.triangles, T, k), w = corner(m.triangles, T, (k + 1) % 3),
                   x = corner(m.triangles, T, (k + 2) % 3);
    auto& nb = m.topology.adjacency.neighbour;
    const uint32_t nb_wx = nb[T][(k + 1) % 3];
    set_corner(m.triangles, T, (k + 1) % 3, q);  // T = (u, q, x)
    const uint32_t T2 = add_triangle(m, q, w, x);
    nb[T][k] = kInvalidIndex;  // (u, q): linked below
    nb[T][(k + 1) % 3] = T2;   // (q, x)
    nb[T2] = {kInvalidIndex, nb_wx, T};
    set_link(m, nb_wx, w, x, T2);
    m.topology.vertex_triangle[w] = T2;
    pieces.push_back(u == a ? Piece{T, T2} : Piece{T2, T});
    all.push_back(T), all.push_back(T2);
    remove_spring(m, a, b);
    add_spring(m, a, q), add_spring(m, q, b), add_spring(m, q, x);
  }
  if (linked) {
    set_link(m, pieces[0].with_a, a, q, pieces[1].with_a);
    set_link(m, pieces[1].with_a, a, q, pieces[0].with_a);
    set_link(m, pieces[0].with_b, q, b, pieces[1].with_b);
    set_link(m, pieces[1].with_b, q, b, pieces[0].with_b);
  }
  m.topology.vertex_triangle[q] = all[0];
  log.new_particles.push_back(q);
  log.origins.push_back({q, {a, b, kInvalidIndex}, {1.0 - t, t, 0.0}});
  log.touched_triangles.insert(log.touched_triangles.end(), all.begin(), all.end());
  ++log.edge_splits;
  if (!linked && tris.size() == 2)
    separate_wedges(m, q, all, log);  // a slit grows an inner point: it opens
  return q;
}

uint32_t split_face(CutMesh& m, uint32_t tri, const Vec3& bary, EditLog& log) {
  if (!m.triangles.slots.alive(tri) || !bary.allFinite())
    throw std::invalid_argument("split_face: triangle " + std::to_string(tri) +
                                " is dead or the weights are not finite");
  Triangles& tr = m.triangles;
  const uint32_t a = tr.a[tri], b = tr.b[tri], c = tr.c[tri];
  const Vec3 w = bary.cwiseMax(0.0) / bary.cwiseMax(0.0).sum();
  // Blend a and b, then the result and c: the same weights, two steps.
  const uint32_t q = add_particle(m, a, b, w[1] + w[0] > 0 ? w[1] / (w[0] + w[1]) : 0.0);
  {
    Particles& p = m.particles;
    MembraneTopology& g = m.topology;
    const double s = w[2];
    const auto blend = [&](auto& col) {
      using T = std::decay_t<decltype(col[0])>;
      col[q] = static_cast<T>((1.0 - s) * col[q] + s * col[c]);
    };
    blend(p.x), blend(p.y), blend(p.z), blend(p.vx), blend(p.vy), blend(p.vz);
    blend(g.rest_x), blend(g.rest_y), blend(g.rest_z);
    const bool anchored = p.kind[a] == ParticleKind::Anchored &&
                          p.kind[b] == ParticleKind::Anchored &&
                          p.kind[c] == ParticleKind::Anchored;
    p.kind[q] = anchored ? ParticleKind::Anchored : ParticleKind::Free;
    p.inv_mass[q] =
        anchored ? 0.0f : std::max({p.inv_mass[a], p.inv_mass[b], p.inv_mass[c], p.inv_mass[q]});
  }
  auto& nb = m.topology.adjacency.neighbour;
  const uint32_t nb_bc = nb[tri][1], nb_ca = nb[tri][2];
  tr.c[tri] = q;  // (a, b, q)
  const uint32_t t1 = add_triangle(m, b, c, q), t2 = add_triangle(m, c, a, q);
  nb[tri][1] = t1, nb[tri][2] = t2;
  nb[t1] = {nb_bc, t2, tri};
  nb[t2] = {nb_ca, tri, t1};
  set_link(m, nb_bc, b, c, t1);
  set_link(m, nb_ca, c, a, t2);
  m.topology.vertex_triangle[c] = t1;
  m.topology.vertex_triangle[q] = tri;
  add_spring(m, a, q), add_spring(m, b, q), add_spring(m, c, q);
  log.new_particles.push_back(q);
  log.origins.push_back({q, {a, b, c}, {w[0], w[1], w[2]}});
  log.touched_triangles.insert(log.touched_triangles.end(), {tri, t1, t2});
  ++log.face_splits;
  return q;
}

bool open_edge(CutMesh& m, uint32_t p, uint32_t q, EditLog& log) {
  std::vector<uint32_t> tris;
  triangles_on_edge(m, p, q, tris);
  if (tris.size() != 2) return false;
  const auto directed = [&](uint32_t t) {
    const int k = corner_slot(m.triangles, t, p);
    return corner(m.triangles, t, (k + 1) % 3) == q;
  };
  const uint32_t L = directed(tris[0]) ? tris[0] : tris[1], R = L == tris[0] ? tris[1] : tris[0];
  const bool linked = link_across(m, L, p, q) == R;
  if (linked) {
    set_link(m, L, p, q, kInvalidIndex);
    set_link(m, R, p, q, kInvalidIndex);
    ++log.opened_edges;
  }
  const std::vector<uint32_t> sides{L, R};
  separate_wedges(m, p, sides, log);
  separate_wedges(m, q, sides, log);
  log.touched_triangles.push_back(L);
  log.touched_triangles.push_back(R);
  return linked;
}

bool merge_along_cut(CutMesh& m, uint32_t v, double max_turn_deg, double min_angle, EditLog& log) {
  Particles& p = m.particles;
  if (!p.slots.alive(v) || p.kind[v] != ParticleKind::Free) return false;
  const uint32_t h = m.topology.vertex_triangle[v];
  if (!m.triangles.slots.alive(h)) return false;
  std::vector<uint32_t> fan;
  vertex_fan(m.triangles, m.topology.adjacency, h, v, fan);
  if (fan.size() != 2) return false;
  Triangles& tr = m.triangles;
  auto& nb = m.topology.adjacency.neighbour;
  // Name them so A = (v, m2, x) and B = (v, x, m1) in winding order: the quad is (v, m2, x, m1).
  uint32_t A = fan[0], B = fan[1];
  auto next_of = [&](uint32_t t, int d) { return corner(tr, t, (corner_slot(tr, t, v) + d) % 3); };
  if (next_of(A, 2) != next_of(B, 1)) std::swap(A, B);
  if (next_of(A, 2) != next_of(B, 1)) return false;
  const uint32_t x = next_of(A, 2), m2 = next_of(A, 1), m1 = next_of(B, 2);
  if (m1 == m2 || link_across(m, A, v, x) != B) return false;
  if (link_across(m, A, v, m2) != kInvalidIndex || link_across(m, B, m1, v) != kInvalidIndex)
    return false;
  if (m.topology.spring_of_edge.count(edge_key(m1, m2))) return false;
  const auto pos = [&](uint32_t i) { return cut::particle_position(p, i); };
  if (angle_deg(pos(v) - pos(m1), pos(m2) - pos(v)) >= max_turn_deg) return false;
  const auto rest = [&](uint32_t i) { return rest_position(m.topology, i); };
  if (angle_deg(rest(v) - rest(m1), rest(m2) - rest(v)) >= max_turn_deg) return false;
  if (min_angle_deg(pos(m2), pos(x), pos(m1)) < min_angle ||
      min_angle_deg(rest(m2), rest(x), rest(m1)) < min_angle)
    return false;
  const Vec3 nA = (pos(m2) - pos(v)).cross(pos(x) - pos(v)),
             nB = (pos(x) - pos(v)).cross(pos(m1) - pos(v));
  const Vec3 nC = (pos(x) - pos(m2)).cross(pos(m1) - pos(m2));
  if (nC.dot(nA + nB) <= 0.0) return false;

  const uint32_t nb_m2x = link_across(m, A, m2, x), nb_xm1 = link_across(m, B, x, m1);
  tr.a[A] = m2, tr.b[A] = x, tr.c[A] = m1;
  nb[A] = {nb_m2x, nb_xm1, kInvalidIndex};
  set_link(m, nb_xm1, x, m1, A);
  nb[B] = {kInvalidIndex, kInvalidIndex, kInvalidIndex};
  table_remove(tr, B);
  remove_spring(m, v, m1), remove_spring(m, v, m2), remove_spring(m, v, x);
  add_spring(m, m1, m2);
  table_remove(p, v);
  m.topology.vertex_triangle[v] = kInvalidIndex;
  m.topology.vertex_triangle[m1] = m.topology.vertex_triangle[m2] = m.topology.vertex_triangle[x] =
      A;
  log.removed_particles.push_back(v);
  log.touched_triangles.push_back(A);
  ++log.merges;
  return true;
}

std::string check_topology(const CutMesh& m) {
  const Triangles& tr = m.triangles;
  const MembraneTopology& g = m.topology;
  const uint32_t nt = tr.slots.size(), np = m.particles.slots.size();
  if (g.adjacency.neighbour.size() != nt) return "adjacency has the wrong size";
  if (g.vertex_triangle.size() < np || g.rest_x.size() < np) return "per-particle arrays too short";
  const TriangleAdjacency fresh = build_triangle_adjacency(tr, np);
  for (uint32_t t = 0; t < nt; ++t) {
    if (!tr.slots.alive(t)) continue;
    for (int k = 0; k < 3; ++k) {
      const uint32_t n = g.adjacency.neighbour[t][k];
      const uint32_t u = corner(tr, t, k), v = corner(tr, t, (k + 1) % 3);
      if (n != kInvalidIndex) {
        if (n != fresh.neighbour[t][k])
          return "triangle " + std::to_string(t) + " edge " + std::to_string(k) + " links " +
                 std::to_string(n) + ", a fresh adjacency says " +
                 std::to_string(fresh.neighbour[t][k]);
        if (edge_slot(tr, n, u, v) < 0 || g.adjacency.neighbour[n][edge_slot(tr, n, u, v)] != t)
          return "link " + std::to_string(t) + " -> " + std::to_string(n) + " is not mutual";
      }
      if (!g.spring_of_edge.count(edge_key(u, v)))
        return "edge (" + std::to_string(u) + ", " + std::to_string(v) + ") has no indexed spring";
    }
  }
  for (uint32_t v = 0; v < np; ++v) {
    if (!m.particles.slots.alive(v) || g.vertex_triangle[v] == kInvalidIndex) continue;
    const uint32_t h = g.vertex_triangle[v];
    if (!tr.slots.alive(h) || corner_slot(tr, h, v) < 0)
      return "particle " + std::to_string(v) + "'s hint triangle " + std::to_string(h) +
             " does not hold it";
  }
  size_t live = 0;
  for (uint32_t e = 0; e < m.springs.slots.size(); ++e) live += m.springs.slots.alive(e);
  if (live != g.spring_of_edge.size())
    return std::to_string(live) + " live springs but " + std::to_string(g.spring_of_edge.size()) +
           " indexed";
  for (const auto& [key, e] : g.spring_of_edge) {
    if (!m.springs.slots.alive(e) || edge_key(m.springs.i[e], m.springs.j[e]) != key)
      return "spring index names spring " + std::to_string(e) + " for another pair";
  }
  return "";
}

void refresh_since(CutMesh& m, EditLog& log, size_t touched_before) {
  EditLog region;
  region.touched_triangles.assign(
      log.touched_triangles.begin() + static_cast<std::ptrdiff_t>(touched_before),
      log.touched_triangles.end());
  refresh_region(m, region);
  log.clamped_pretension += region.clamped_pretension;
}

void refresh_region(CutMesh& m, EditLog& log) {
  // After a batch of edits: every live triangle and spring names a particle slot, and the
  // per-triangle and per-particle arrays cover the tables (check_topology says more, slower).
  [[maybe_unused]] const size_t np = m.particles.slots.size();
  assert(live_all_below(m.triangles.slots, {m.triangles.a, m.triangles.b, m.triangles.c}, np));
  assert(live_all_below(m.springs.slots, {m.springs.i, m.springs.j}, np));
  assert(m.topology.adjacency.neighbour.size() == m.triangles.slots.size());
  assert(same_size(m.topology.rest_x, m.topology.rest_y, m.topology.rest_z) &&
         m.topology.rest_x.size() >= np && m.topology.vertex_triangle.size() >= np);
  std::vector<uint32_t> tris = log.touched_triangles, on_edge, fan, corners;
  std::sort(tris.begin(), tris.end());
  tris.erase(std::unique(tris.begin(), tris.end()), tris.end());
  const Triangles& tr = m.triangles;
  for (uint32_t t : tris) {
    if (!tr.slots.alive(t)) continue;
    for (int k = 0; k < 3; ++k) {
      const uint32_t u = corner(tr, t, k), w = corner(tr, t, (k + 1) % 3);
      push_unique(corners, u);
      const auto it = m.topology.spring_of_edge.find(edge_key(u, w));
      if (it == m.topology.spring_of_edge.end())
        throw std::logic_error("refresh_region: an edge lost its spring");
      triangles_on_edge(m, u, w, on_edge);
      double area = 0.0, half_cot = 0.0;
      for (uint32_t e : on_edge) {
        const int ke = edge_slot(tr, e, u, w);
        const uint32_t o = corner(tr, e, (ke + 2) % 3);
        const Vec3 ro = rest_position(m.topology, o);
        const Vec3 du = rest_position(m.topology, u) - ro, dw = rest_position(m.topology, w) - ro;
        const double cross = du.cross(dw).norm();
        area += 0.5 * cross;
        half_cot += cross > 0 ? 0.5 * du.dot(dw) / cross : 0.0;
      }
      const double length = (rest_position(m.topology, u) - rest_position(m.topology, w)).norm();
      const springs::SpringConstants sc =
          springs::edge_spring_constants(m.material.springs, length, area, half_cot);
      log.clamped_pretension += sc.pretension_clamped;
      m.springs.stiffness[it->second] = static_cast<float>(sc.stiffness);
      m.springs.rest_length[it->second] = static_cast<float>(sc.rest_length);
    }
  }
  if (m.material.areal_density_kg_mm2 <= 0.0) return;
  for (uint32_t v : corners) {
    if (m.particles.kind[v] == ParticleKind::Anchored) {
      m.particles.inv_mass[v] = 0.0f;
      continue;
    }
    vertex_fan(tr, m.topology.adjacency, m.topology.vertex_triangle[v], v, fan);
    double area = 0.0;
    for (uint32_t t : fan) area += rest_area(m, t);
    const double mass = m.material.areal_density_kg_mm2 * area / 3.0;
    m.particles.inv_mass[v] = mass > 0 ? static_cast<float>(1.0 / mass) : 0.0f;
  }
}

}  // namespace phaco::cut
