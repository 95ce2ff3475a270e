#include "systems/cut/vertex_insertion.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

#include "systems/cut/edit_detail.hpp"

namespace phaco::cut {
namespace {

constexpr double kRestoreMinAreaMm2 = 1e-8;  // systems/topology_check's default thresholds
constexpr double kRestoreMinAngleDeg = 1.0;

std::array<uint32_t, 3> corners_of(const Triangles& tr, uint32_t t) {
  return {tr.a[t], tr.b[t], tr.c[t]};
}

// Records the star of the new vertex (its fan, reached from its hint) after a split.
void record_star(const CutMesh& m, VertexInsertion& ins) {
  std::vector<uint32_t> fan;
  vertex_fan(m.triangles, m.topology.adjacency, m.topology.vertex_triangle[ins.vertex], ins.vertex,
             fan);
  if (fan.size() != (ins.kind == CutPoint::Face ? 3u : 2u * ins.original_count))
    throw std::logic_error("split recording: the new vertex has " + std::to_string(fan.size()) +
                           " triangles");
  ins.piece_count = static_cast<uint32_t>(fan.size());
  for (size_t i = 0; i < fan.size(); ++i) {
    ins.piece_slot[i] = fan[i];
    ins.piece_corners[i] = corners_of(m.triangles, fan[i]);
    ins.piece_links[i] = m.topology.adjacency.neighbour[fan[i]];
  }
}

}  // namespace

bool is_slit(const CutMesh& m, uint32_t a, uint32_t b) {
  std::vector<uint32_t> tris;
  triangles_on_edge(m, a, b, tris);
  return tris.size() == 2 && detail::link_across(m, tris[0], a, b) != tris[1];
}

VertexInsertion split_face_recorded(CutMesh& m, uint32_t tri, const Vec3& bary, EditLog& log) {
  VertexInsertion ins;
  ins.kind = CutPoint::Face;
  ins.original_count = 1;
  ins.original_slot[0] = tri;
  if (m.triangles.slots.alive(tri)) ins.original_corners[0] = corners_of(m.triangles, tri);
  ins.vertex = split_face(m, tri, bary, log);  // throws on a dead triangle or bad weights
  ins.weights = bary.cwiseMax(0.0) / bary.cwiseMax(0.0).sum();
  record_star(m, ins);
  return ins;
}

VertexInsertion split_edge_recorded(CutMesh& m, uint32_t a, uint32_t b, double t, EditLog& log) {
  std::vector<uint32_t> tris;
  triangles_on_edge(m, a, b, tris);
  if (tris.size() > 2 || is_slit(m, a, b))
    throw std::invalid_argument("split_edge_recorded: (" + std::to_string(a) + ", " +
                                std::to_string(b) +
                                ") is a slit or non-manifold edge; its split cannot be undone");
  VertexInsertion ins;
  ins.kind = CutPoint::Edge;
  ins.a = a, ins.b = b;
  ins.original_count = static_cast<uint32_t>(tris.size());
  for (size_t i = 0; i < tris.size(); ++i) {
    ins.original_slot[i] = tris[i];
    ins.original_corners[i] = corners_of(m.triangles, tris[i]);
  }
  ins.vertex = split_edge(m, a, b, t, log);  // throws on a non-edge or t outside (0, 1)
  ins.weights = Vec3(1.0 - t, t, 0.0);
  record_star(m, ins);
  return ins;
}

InsertionState insertion_state(const CutMesh& m, const VertexInsertion& ins) {
  const uint32_t q = ins.vertex;
  if (ins.kind == CutPoint::Vertex || q == kInvalidIndex || !m.particles.slots.alive(q))
    return InsertionState::Gone;
  const Triangles& tr = m.triangles;
  for (uint32_t i = 0; i < ins.piece_count; ++i) {
    const uint32_t t = ins.piece_slot[i];
    if (!tr.slots.alive(t) || corners_of(tr, t) != ins.piece_corners[i])
      return InsertionState::Changed;
    for (int k = 0; k < 3; ++k) {
      const bool through_q = corner(tr, t, k) == q || corner(tr, t, (k + 1) % 3) == q;
      if (through_q && m.topology.adjacency.neighbour[t][k] != ins.piece_links[i][k])
        return InsertionState::Changed;
    }
  }
  for (uint32_t i = 0; i < ins.original_count; ++i) {
    const auto& c = ins.original_corners[i];
    const Vec3 p0 = particle_position(m.particles, c[0]), p1 = particle_position(m.particles, c[1]),
               p2 = particle_position(m.particles, c[2]);
    if (0.5 * (p1 - p0).cross(p2 - p0).norm() < kRestoreMinAreaMm2 ||
        min_angle_deg(p0, p1, p2) < kRestoreMinAngleDeg)
      return InsertionState::Degenerate;
  }
  return InsertionState::Intact;
}

bool remove_inserted_vertex(CutMesh& m, const VertexInsertion& ins, EditLog& log) {
  if (insertion_state(m, ins) != InsertionState::Intact) return false;
  const uint32_t q = ins.vertex;
  Triangles& tr = m.triangles;
  auto& nb = m.topology.adjacency.neighbour;
  const auto is_original = [&](uint32_t t) {
    for (uint32_t i = 0; i < ins.original_count; ++i)
      if (ins.original_slot[i] == t) return true;
    return false;
  };
  // The outer links of the originals, read from the pieces before they change.
  std::array<std::array<uint32_t, 3>, 2> outer{};
  for (uint32_t i = 0; i < ins.original_count; ++i) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t u = ins.original_corners[i][k], v = ins.original_corners[i][(k + 1) % 3];
      if (ins.kind == CutPoint::Edge && edge_key(u, v) == edge_key(ins.a, ins.b)) {
        outer[i][k] = ins.original_count == 2 ? ins.original_slot[1 - i] : kInvalidIndex;
        continue;
      }
      outer[i][k] = kInvalidIndex;
      for (uint32_t j = 0; j < ins.piece_count; ++j)
        if (detail::edge_slot(tr, ins.piece_slot[j], u, v) >= 0)
          outer[i][k] = detail::link_across(m, ins.piece_slot[j], u, v);
    }
  }
  // The vertex's neighbours, for its springs.
  std::vector<uint32_t> ring;
  for (uint32_t j = 0; j < ins.piece_count; ++j)
    for (uint32_t c : ins.piece_corners[j])
      if (c != q) detail::push_unique(ring, c);
  for (uint32_t j = 0; j < ins.piece_count; ++j) {
    const uint32_t t = ins.piece_slot[j];
    if (is_original(t)) continue;
    nb[t] = {kInvalidIndex, kInvalidIndex, kInvalidIndex};
    table_remove(tr, t);
  }
  for (uint32_t i = 0; i < ins.original_count; ++i) {
    const uint32_t t = ins.original_slot[i];
    const auto& c = ins.original_corners[i];
    tr.a[t] = c[0], tr.b[t] = c[1], tr.c[t] = c[2];
    nb[t] = outer[i];
    for (int k = 0; k < 3; ++k)
      if (outer[i][k] != kInvalidIndex && !is_original(outer[i][k]))
        detail::set_link(m, outer[i][k], c[k], c[(k + 1) % 3], t);
    for (uint32_t v : c) m.topology.vertex_triangle[v] = t;
    log.touched_triangles.push_back(t);
  }
  for (uint32_t n : ring) detail::remove_spring(m, q, n);
  if (ins.kind == CutPoint::Edge) detail::add_spring(m, ins.a, ins.b);
  table_remove(m.particles, q);
  m.topology.vertex_triangle[q] = kInvalidIndex;
  log.removed_particles.push_back(q);
  return true;
}

double edge_split_min_angle(const CutMesh& m, uint32_t a, uint32_t b, double t) {
  std::vector<uint32_t> tris;
  triangles_on_edge(m, a, b, tris);
  const auto pos = [&](uint32_t v) { return particle_position(m.particles, v); };
  const auto rest = [&](uint32_t v) { return rest_position(m.topology, v); };
  const Vec3 q = (1 - t) * pos(a) + t * pos(b), rq = (1 - t) * rest(a) + t * rest(b);
  double worst = 180.0;
  for (uint32_t T : tris) {
    uint32_t x = kInvalidIndex;
    for (int k = 0; k < 3; ++k)
      if (corner(m.triangles, T, k) != a && corner(m.triangles, T, k) != b)
        x = corner(m.triangles, T, k);
    worst = std::min({worst, min_angle_deg(pos(a), q, pos(x)), min_angle_deg(q, pos(b), pos(x)),
                      min_angle_deg(rest(a), rq, rest(x)), min_angle_deg(rq, rest(b), rest(x))});
  }
  return tris.empty() ? 0.0 : worst;
}

double face_split_min_angle(const CutMesh& m, uint32_t T, const Vec3& bary) {
  const Vec3 w = bary.cwiseMax(0.0) / bary.cwiseMax(0.0).sum();
  double worst = 180.0;
  for (int shape = 0; shape < 2; ++shape) {
    Vec3 c[3];
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = corner(m.triangles, T, k);
      c[k] = shape == 0 ? particle_position(m.particles, v) : rest_position(m.topology, v);
    }
    const Vec3 q = w[0] * c[0] + w[1] * c[1] + w[2] * c[2];
    worst = std::min({worst, min_angle_deg(c[0], c[1], q), min_angle_deg(c[1], c[2], q),
                      min_angle_deg(c[2], c[0], q)});
  }
  return worst;
}

}  // namespace phaco::cut
