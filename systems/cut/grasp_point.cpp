#include "systems/cut/grasp_point.hpp"

#include <algorithm>
#include <array>
#include <stdexcept>
#include <string>
#include <vector>

namespace phaco::cut {
namespace {

bool anchored(const CutMesh& m, uint32_t v) {
  return m.particles.kind[v] == ParticleKind::Anchored;
}

Vec3 velocity(const Particles& p, uint32_t v) {
  return {p.vx[v], p.vy[v], p.vz[v]};
}

void set_velocity(Particles& p, uint32_t v, const Vec3& u) {
  p.vx[v] = static_cast<float>(u.x());
  p.vy[v] = static_cast<float>(u.y());
  p.vz[v] = static_cast<float>(u.z());
}

GraspPoint at_vertex(const CutMesh& m, uint32_t v, double moved) {
  GraspPoint g;
  if (anchored(m, v)) return g;  // held by the zonules: the forceps cannot take it
  g.particle = v;
  g.kind = CutPoint::Vertex;
  g.moved_mm = moved;
  return g;
}

// An edge point that may be split: inside the edge, not wholly anchored, not a slit, and leaving
// no angle under the cutter's minimum.
bool edge_splittable(const CutMesh& m, uint32_t a, uint32_t b, double t, const CutSettings& s) {
  if (!(t > 0.0 && t < 1.0) || (anchored(m, a) && anchored(m, b))) return false;
  std::vector<uint32_t> tris;
  triangles_on_edge(m, a, b, tris);
  if (tris.empty() || tris.size() > 2 || is_slit(m, a, b)) return false;
  return edge_split_min_angle(m, a, b, t) >= s.min_angle_deg;
}

GraspPoint split_on_edge(CutMesh& m, uint32_t a, uint32_t b, double t, double moved, EditLog& log) {
  GraspPoint g;
  g.insertion = split_edge_recorded(m, a, b, t, log);
  g.particle = g.insertion.vertex;
  g.kind = CutPoint::Edge;
  g.temporary = true;
  g.moved_mm = moved;
  return g;
}

GraspPoint place_and_insert(CutMesh& m, const CutPoint& w, const CutSettings& s, EditLog& log) {
  const auto pos = [&](uint32_t v) { return particle_position(m.particles, v); };
  if (w.kind == CutPoint::Vertex) return at_vertex(m, w.a, 0.0);
  if (w.kind == CutPoint::Edge) {
    if (edge_splittable(m, w.a, w.b, w.t, s)) return split_on_edge(m, w.a, w.b, w.t, 0.0, log);
    const uint32_t end = w.t < 0.5 ? w.a : w.b;
    return at_vertex(m, end, (pos(end) - w.position).norm());
  }
  // Inside triangle T.
  const uint32_t T = w.triangle;
  const uint32_t c[3] = {m.triangles.a[T], m.triangles.b[T], m.triangles.c[T]};
  const bool all_anchored = anchored(m, c[0]) && anchored(m, c[1]) && anchored(m, c[2]);
  if (!all_anchored && face_split_min_angle(m, T, w.bary) >= s.min_angle_deg) {
    GraspPoint g;
    g.insertion = split_face_recorded(m, T, w.bary, log);
    g.particle = g.insertion.vertex;
    g.kind = CutPoint::Face;
    g.temporary = true;
    return g;
  }
  // The quality snap: the nearest edge that can take the point, then the nearest corner.
  std::array<int, 3> order{0, 1, 2};
  std::array<double, 3> dist{}, along{};
  for (int k = 0; k < 3; ++k) {
    const Vec3 a = pos(c[k]), e = pos(c[(k + 1) % 3]) - a;
    const double len2 = e.squaredNorm();
    along[k] = len2 > 0 ? std::clamp((w.position - a).dot(e) / len2, 0.0, 1.0) : 0.0;
    dist[k] = (w.position - (a + along[k] * e)).norm();
  }
  std::sort(order.begin(), order.end(),
            [&](int i, int j) { return dist[i] < dist[j] || (dist[i] == dist[j] && i < j); });
  for (int k : order)
    if (edge_splittable(m, c[k], c[(k + 1) % 3], along[k], s))
      return split_on_edge(m, c[k], c[(k + 1) % 3], along[k], dist[k], log);
  int nearest = 0;
  for (int k = 1; k < 3; ++k)
    if ((pos(c[k]) - w.position).norm() < (pos(c[nearest]) - w.position).norm()) nearest = k;
  return at_vertex(m, c[nearest], (pos(c[nearest]) - w.position).norm());
}

}  // namespace

GraspPoint grasp_at(CutMesh& m, const CutPoint& where, const CutSettings& s, EditLog& log) {
  const auto live_particle = [&](uint32_t v) {
    return v < m.particles.slots.size() && m.particles.slots.alive(v);
  };
  const bool ok = where.position.allFinite() &&
                  (where.kind == CutPoint::Vertex ? live_particle(where.a)
                   : where.kind == CutPoint::Edge
                       ? live_particle(where.a) && live_particle(where.b)
                       : where.triangle < m.triangles.slots.size() &&
                             m.triangles.slots.alive(where.triangle) && where.bary.allFinite());
  if (!ok)
    throw std::invalid_argument(
        "grasp_at: the grasp point names a dead triangle or particle, or is not finite");
  const size_t touched_before = log.touched_triangles.size();
  GraspPoint g = place_and_insert(m, where, s, log);
  if (g.temporary) refresh_since(m, log, touched_before);
  return g;
}

GraspPoint grasp_near(CutMesh& m, const Vec3& tip, uint32_t start_triangle, const CutSettings& s,
                      EditLog& log) {
  const CutPoint where =
      locate_cut_point(m.particles, m.triangles, m.topology.adjacency, start_triangle, tip, s.snap);
  return grasp_at(m, where, s, log);
}

ReleaseReport release(CutMesh& m, GraspPoint& g, EditLog& log) {
  ReleaseReport r;
  if (!g.held()) return r;
  r.released = true;
  if (g.temporary) {
    const VertexInsertion& ins = g.insertion;
    r.state = insertion_state(m, ins);
    if (r.state == InsertionState::Intact) {
      Particles& p = m.particles;
      const uint32_t q = ins.vertex;
      const Vec3 momentum_q =
          p.inv_mass[q] > 0 ? Vec3(velocity(p, q) / p.inv_mass[q]) : Vec3::Zero();
      // The corners the vertex's weights refer to, and their momentum now.
      std::array<uint32_t, 3> corners{ins.a, ins.b, kInvalidIndex};
      if (ins.kind == CutPoint::Face) corners = ins.original_corners[0];
      std::array<Vec3, 3> momentum{};
      std::array<bool, 3> free{};
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = corners[k];
        free[k] = v != kInvalidIndex && p.kind[v] == ParticleKind::Free && p.inv_mass[v] > 0;
        if (free[k]) momentum[k] = velocity(p, v) / p.inv_mass[v];
      }
      const size_t touched_before = log.touched_triangles.size();
      remove_inserted_vertex(m, ins, log);
      refresh_since(m, log, touched_before);
      for (int k = 0; k < 3; ++k)
        if (free[k] && p.inv_mass[corners[k]] > 0)
          set_velocity(p, corners[k],
                       (momentum[k] + ins.weights[k] * momentum_q) * p.inv_mass[corners[k]]);
      r.removed_temporary = true;
    } else if (r.state != InsertionState::Gone) {
      r.kept_temporary = true;
    }
  }
  g = GraspPoint{};
  return r;
}

}  // namespace phaco::cut
