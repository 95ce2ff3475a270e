#include "systems/cut/progressive_cut.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace phaco::cut {
namespace {

constexpr double kReachTol = 1e-9;  // exit parameter this close to 1: the point is in the triangle
constexpr double kStuckTol = 1e-9;  // exit parameter this close to 0: no way forward

// Where a cut point will become a mesh vertex.
struct Placement {
  CutPoint::Kind kind = CutPoint::Vertex;
  uint32_t triangle = kInvalidIndex;              // Face
  Vec3 bary = Vec3::Zero();                       // Face: weights of the triangle's corners
  uint32_t a = kInvalidIndex, b = kInvalidIndex;  // Edge ends; Vertex: a
  double t = 0.0;                                 // Edge: from a
  double moved_mm = 0.0;                          // how far snapping moved the point
};

Vec3 pos(const CutMesh& m, uint32_t v) {
  return particle_position(m.particles, v);
}

// Smallest angle a split would leave, over the current and the rest shape.
double edge_split_quality(const CutMesh& m, uint32_t a, uint32_t b, double t) {
  std::vector<uint32_t> tris;
  triangles_on_edge(m, a, b, tris);
  const Vec3 q = (1 - t) * pos(m, a) + t * pos(m, b);
  const Vec3 rq = (1 - t) * rest_position(m.topology, a) + t * rest_position(m.topology, b);
  double worst = 180.0;
  for (uint32_t T : tris) {
    uint32_t x = kInvalidIndex;
    for (int k = 0; k < 3; ++k)
      if (corner(m.triangles, T, k) != a && corner(m.triangles, T, k) != b)
        x = corner(m.triangles, T, k);
    const Vec3 rx = rest_position(m.topology, x);
    worst = std::min({worst, min_angle_deg(pos(m, a), q, pos(m, x)),
                      min_angle_deg(q, pos(m, b), pos(m, x)),
                      min_angle_deg(rest_position(m.topology, a), rq, rx),
                      min_angle_deg(rq, rest_position(m.topology, b), rx)});
  }
  return tris.empty() ? 0.0 : worst;
}

double face_split_quality(const CutMesh& m, uint32_t T, const Vec3& w) {
  double worst = 180.0;
  for (int shape = 0; shape < 2; ++shape) {
    Vec3 c[3];
    for (int k = 0; k < 3; ++k)
      c[k] = shape == 0 ? pos(m, corner(m.triangles, T, k))
                        : rest_position(m.topology, corner(m.triangles, T, k));
    const Vec3 q = w[0] * c[0] + w[1] * c[1] + w[2] * c[2];
    worst = std::min({worst, min_angle_deg(c[0], c[1], q), min_angle_deg(c[1], c[2], q),
                      min_angle_deg(c[2], c[0], q)});
  }
  return worst;
}

Placement at_vertex(uint32_t v, double moved) {
  Placement p;
  p.kind = CutPoint::Vertex;
  p.a = v;
  p.moved_mm = moved;
  return p;
}

// The placement of a point with weights w in triangle T: proximity snap to a vertex, then an edge,
// then the quality check (a refused split goes to the nearest edge, then the nearest corner).
// `exclude` is a corner never chosen (the vertex the walk stands on), if possible.
Placement place(const CutMesh& m, uint32_t T, Vec3 w, const CutSettings& s, uint32_t exclude) {
  w = w.cwiseMax(0.0);
  w /= w.sum();
  Vec3 X[3];
  for (int k = 0; k < 3; ++k) X[k] = pos(m, corner(m.triangles, T, k));
  const Vec3 x = w[0] * X[0] + w[1] * X[1] + w[2] * X[2];
  int nearest_v = -1;
  double nearest_vd = 1e300;
  for (int k = 0; k < 3; ++k) {
    if (corner(m.triangles, T, k) == exclude) continue;
    const double d = (x - X[k]).norm();
    if (d < nearest_vd) nearest_vd = d, nearest_v = k;
  }
  if (nearest_v >= 0 && (nearest_vd <= s.snap.vertex_snap_mm || w[nearest_v] >= 1.0 - 1e-12))
    return at_vertex(corner(m.triangles, T, nearest_v), nearest_vd);

  // Edges by distance; an edge through `exclude` is allowed (the cut then runs along it).
  int order[3] = {0, 1, 2};
  double dist[3], along[3];
  for (int k = 0; k < 3; ++k) {
    const Vec3 e = X[(k + 1) % 3] - X[k];
    const double len2 = e.squaredNorm();
    along[k] = len2 > 0 ? std::clamp((x - X[k]).dot(e) / len2, 0.0, 1.0) : 0.0;
    dist[k] = (x - (X[k] + along[k] * e)).norm();
  }
  std::sort(order, order + 3, [&](int i, int j) { return dist[i] < dist[j]; });
  const bool on_edge = dist[order[0]] <= s.snap.edge_snap_mm || w[(order[0] + 2) % 3] <= 1e-12;
  if (!on_edge && face_split_quality(m, T, w) >= s.min_angle_deg) {
    Placement p;
    p.kind = CutPoint::Face;
    p.triangle = T;
    p.bary = w;
    return p;
  }
  const int k = order[0];
  const uint32_t a = corner(m.triangles, T, k), b = corner(m.triangles, T, (k + 1) % 3);
  const double t = along[k];
  if (t > 0.0 && t < 1.0 && edge_split_quality(m, a, b, t) >= s.min_angle_deg) {
    Placement p;
    p.kind = CutPoint::Edge;
    p.a = a, p.b = b, p.t = t;
    p.moved_mm = dist[k];
    return p;
  }
  if (nearest_v >= 0) return at_vertex(corner(m.triangles, T, nearest_v), nearest_vd);
  return at_vertex(exclude, (x - pos(m, exclude)).norm());
}

uint32_t realise(CutMesh& m, const Placement& p, EditLog& log) {
  switch (p.kind) {
    case CutPoint::Face:
      return split_face(m, p.triangle, p.bary, log);
    case CutPoint::Edge:
      return split_edge(m, p.a, p.b, p.t, log);
    default:
      return p.a;
  }
}

// Is v within `hops` free (boundary) edges of `tip`?
bool own_lip(const CutMesh& m, uint32_t tip, uint32_t v, uint32_t hops) {
  std::vector<uint32_t> frontier{tip}, seen{tip}, next, fan;
  for (uint32_t h = 0; h < hops && !frontier.empty(); ++h) {
    next.clear();
    for (uint32_t u : frontier) {
      const uint32_t hint = m.topology.vertex_triangle[u];
      if (!m.triangles.slots.alive(hint)) continue;
      vertex_fan(m.triangles, m.topology.adjacency, hint, u, fan);
      for (uint32_t t : fan) {
        const int k = corner_slot(m.triangles, t, u);
        const auto& nb = m.topology.adjacency.neighbour[t];
        const uint32_t ends[2] = {
            nb[k] == kInvalidIndex ? corner(m.triangles, t, (k + 1) % 3) : kInvalidIndex,
            nb[(k + 2) % 3] == kInvalidIndex ? corner(m.triangles, t, (k + 2) % 3) : kInvalidIndex};
        for (uint32_t w : ends) {
          if (w == kInvalidIndex || std::find(seen.begin(), seen.end(), w) != seen.end()) continue;
          if (w == v) return true;
          seen.push_back(w);
          next.push_back(w);
        }
      }
    }
    frontier.swap(next);
  }
  return false;
}

}  // namespace

std::string_view to_string(CutCase c) {
  static constexpr std::string_view names[kCutCases] = {"IC1", "IC2", "IC3", "IC4", "IC5",
                                                        "IC6", "SC1", "SC2", "SC3"};
  return names[static_cast<int>(c)];
}

CutCase classify_cut(CutPoint::Kind from, CutPoint::Kind to, bool subsequent) {
  if (subsequent)
    return to == CutPoint::Face ? CutCase::SC1
                                : (to == CutPoint::Edge ? CutCase::SC2 : CutCase::SC3);
  if (from == to)
    return from == CutPoint::Face ? CutCase::IC1
                                  : (from == CutPoint::Edge ? CutCase::IC2 : CutCase::IC3);
  const bool face = from == CutPoint::Face || to == CutPoint::Face;
  const bool edge = from == CutPoint::Edge || to == CutPoint::Edge;
  if (face && edge) return CutCase::IC4;
  if (face) return CutCase::IC5;
  return CutCase::IC6;
}

void end_cut(CutPath& path) {
  path.started = false;
  path.tip = kInvalidIndex;
  path.reached_boundary = false;
  path.direction = Vec3::Zero();
}

bool finish_cut(CutMesh& m, CutPath& path, const CutSettings& settings, double min_angle_deg,
                EditLog& log) {
  bool made = false;
  for (int attempt = 0; attempt < 2; ++attempt) {
    if (path.tip == kInvalidIndex || !m.particles.slots.alive(path.tip) || path.reached_boundary ||
        path.tool_points.size() < 2)
      break;
    const Vec3 end = path.tool_points.back();
    const double gap = (pos(m, path.tip) - end).norm();
    if (gap <= settings.snap.vertex_snap_mm) break;
    CutSettings relaxed = settings;
    relaxed.min_angle_deg = std::min(settings.min_angle_deg, min_angle_deg);
    if (attempt == 1) relaxed.snap.vertex_snap_mm = gap * (1.0 - 1e-9);
    path.tool_points.pop_back();  // cut_towards records the sample again
    made = cut_towards(m, path, end, relaxed, log).made || made;
  }
  return made;
}

namespace {

// Where the tool point lies on the mesh, walked from the last hit. The walk can stop on a lip of
// the cut, the point lying across it: then it walks again from every triangle round the crack tip
// (which joins both sides) and keeps the nearest.
CutPoint locate_target(const CutMesh& m, const CutPath& path, const Vec3& tool_point,
                       const SnapSettings& snap) {
  CutPoint target = locate_cut_point(m.particles, m.triangles, m.topology.adjacency,
                                     path.hint_triangle, tool_point, snap);
  if (path.tip != kInvalidIndex && target.distance_mm > snap.vertex_snap_mm) {
    std::vector<uint32_t> fan;
    vertex_fan(m.triangles, m.topology.adjacency, m.topology.vertex_triangle[path.tip], path.tip,
               fan);
    for (uint32_t t : fan) {
      const CutPoint c =
          locate_cut_point(m.particles, m.triangles, m.topology.adjacency, t, tool_point, snap);
      if (c.distance_mm < target.distance_mm) target = c;
    }
  }
  return target;
}

struct SegmentKinds {
  CutPoint::Kind from, to;
  bool subsequent;  // the path had a tip before this segment
};
struct LogMarks {
  size_t touched_before, new_before;  // the log's sizes when the segment began
};

// After a segment's steps: the path's direction and case counts, the new vertices as the next
// segment's sources, the remesh along the new edges (Fig. 5a), and the physics of the touched
// region refreshed.
void finish_segment(CutMesh& m, CutPath& path, const CutSettings& s, SegmentReport& r, EditLog& log,
                    const std::vector<uint32_t>& visited, const Vec3& start, SegmentKinds kinds,
                    LogMarks marks) {
  const size_t touched_before = marks.touched_before, new_before = marks.new_before;
  if (r.made) {
    const Vec3 d = pos(m, path.tip) - start;
    if (d.norm() > 0) path.direction = d.normalized();
    r.cut_case = classify_cut(kinds.from, kinds.to, kinds.subsequent);
    ++path.case_counts[static_cast<int>(r.cut_case)];
    ++path.span_counts[std::min<uint32_t>(r.triangles_spanned, 3)];
    ++path.segments;
  }
  for (size_t i = new_before; i < log.new_particles.size(); ++i)
    path.sources.push_back(log.new_particles[i]);
  if (s.remesh && r.made) {
    // Fig. 5a: merge pairs along the new path edges (both lips), never at the tip.
    for (size_t i = new_before; i < log.new_particles.size(); ++i) {
      const uint32_t v = log.new_particles[i];
      if (v != path.tip && m.particles.slots.alive(v))
        merge_along_cut(m, v, s.remesh_max_turn_deg, s.min_angle_deg, log);
    }
    for (uint32_t v : visited)
      if (v != path.tip && m.particles.slots.alive(v))
        merge_along_cut(m, v, s.remesh_max_turn_deg, s.min_angle_deg, log);
  }
  refresh_since(m, log, touched_before);
  if (r.reached_boundary) path.reached_boundary = true;
  if (!m.triangles.slots.alive(path.hint_triangle) && m.particles.slots.alive(path.tip))
    path.hint_triangle = m.topology.vertex_triangle[path.tip];
}

// Behind the tip and within slit_mm of the slit's last stretch, taken as straight: the segment from
// the tip back along the last direction, ten slit widths long (lip vertices are too sparse to
// measure from: the remesh merges them along straight cuts).
bool in_own_slit(const CutMesh& m, const CutPath& path, const Vec3& goal, const CutSettings& s) {
  if (!(s.slit_mm > 0) || path.tip == kInvalidIndex || path.direction.squaredNorm() == 0)
    return false;
  const Vec3 from_tip = goal - pos(m, path.tip);
  const double behind = -from_tip.dot(path.direction);
  if (behind <= 0) return false;
  // The slit is no longer than the path itself (from its first vertex to the tip).
  double length = 10.0 * s.slit_mm;
  if (!path.sources.empty() && m.particles.slots.alive(path.sources.front()))
    length = std::min(length, (pos(m, path.tip) - pos(m, path.sources.front())).norm());
  const Vec3 nearest = -std::min(behind, length) * path.direction;
  return (from_tip - nearest).norm() < s.slit_mm;
}

}  // namespace

SegmentReport cut_towards(CutMesh& m, CutPath& path, const Vec3& tool_point, const CutSettings& s,
                          EditLog& log) {
  SegmentReport r;
  if (!tool_point.allFinite())
    throw std::invalid_argument("cut_towards: the tool point is not finite");
  if (path.reached_boundary) {
    r.reached_boundary = true;
    return r;
  }
  path.tool_points.push_back(tool_point);
  const CutPoint target = locate_target(m, path, tool_point, s.snap);
  path.hint_triangle = target.triangle;
  if (!path.started) {
    path.started = true;
    path.first = target;
    return r;
  }
  const size_t touched_before = log.touched_triangles.size(), new_before = log.new_particles.size();
  const bool subsequent = path.tip != kInvalidIndex;
  CutPoint::Kind from_kind = CutPoint::Vertex, to_kind = CutPoint::Vertex;
  if (!subsequent) {
    // The initial cut's first point becomes a vertex (it may have moved since it was sampled: use
    // its position now, located again).
    const CutPoint c0 = locate_cut_point(m.particles, m.triangles, m.topology.adjacency,
                                         path.first.triangle, path.first.position, s.snap);
    const Placement p0 = place(m, c0.triangle, c0.bary, s, kInvalidIndex);
    from_kind = p0.kind;
    path.max_snap_mm = std::max(path.max_snap_mm, p0.moved_mm);
    // Nothing to cut yet; a blade first leaves its own puncture, so that a hand's tremor there
    // does not set the cut's direction.
    if ((c0.position - target.position).norm() <= std::max(s.snap.vertex_snap_mm, s.puncture_mm))
      return r;
    path.tip = realise(m, p0, log);
    path.sources.push_back(path.tip);
  }
  const Vec3 start = pos(m, path.tip);
  const Vec3 goal = target.position;
  if (in_own_slit(m, path, goal, s)) {
    r.stalled = true;
    return r;
  }

  std::vector<uint32_t> fan, visited;
  for (uint32_t step = 0; step < s.max_steps_per_segment; ++step) {
    const uint32_t tip = path.tip;
    if ((pos(m, tip) - goal).norm() <= s.snap.vertex_snap_mm) break;
    vertex_fan(m.triangles, m.topology.adjacency, m.topology.vertex_triangle[tip], tip, fan);
    uint32_t T = kInvalidIndex;
    double best = -1.0;
    Vec3 best_from, best_to;
    for (uint32_t c : fan) {
      Vec3 wt;
      if (!projected_bary(m.particles, m.triangles, c, goal, wt)) continue;
      Vec3 wf = Vec3::Zero();
      wf[corner_slot(m.triangles, c, tip)] = 1.0;
      int exit = -1;
      const double e = exit_parameter(wf, wt, exit);
      if (e > best) T = c, best = e, best_from = wf, best_to = wt;
    }
    if (T == kInvalidIndex || best <= kStuckTol) {
      r.stalled = true;
      break;
    }
    ++r.steps;
    ++r.triangles_spanned;
    const bool arrives = best >= 1.0 - kReachTol;
    Vec3 w = arrives ? best_to : Vec3(best_from + best * (best_to - best_from));
    if (!arrives) w[corner_slot(m.triangles, T, tip)] = 0.0;
    const Placement p = place(m, T, w, s, tip);
    if (p.kind == CutPoint::Vertex && p.a == tip) {
      r.stalled = true;
      break;
    }
    // The point lies inside this triangle but too close to its sides for a good split, and no
    // corner is within the snap distance: the cut waits here for the next sample rather than
    // jump to a far corner.
    if (arrives && p.kind == CutPoint::Vertex && p.moved_mm > s.snap.vertex_snap_mm) break;
    path.max_snap_mm = std::max(path.max_snap_mm, p.moved_mm);
    // Would this point put the path on the rim or an earlier cut?
    bool boundary = false;
    if (p.kind == CutPoint::Vertex) {
      boundary = on_boundary(m, p.a);
    } else if (p.kind == CutPoint::Edge) {
      std::vector<uint32_t> tris;
      triangles_on_edge(m, p.a, p.b, tris);
      boundary = tris.size() != 2 || !joined_edge(m, p.a, p.b);
    }
    // A boundary a few edges from the tip along the free edges is this cut's own lip: stepping
    // onto it is going back or sideways into the incision, not cutting through (a tool lifting
    // off, a sample just behind the tip, a flap dragged over its own cut).
    if (boundary && path.direction.squaredNorm() > 0 &&
        (own_lip(m, tip, p.a, s.own_lip_hops) ||
         (p.kind == CutPoint::Edge && own_lip(m, tip, p.b, s.own_lip_hops)))) {
      r.stalled = true;
      break;
    }
    const uint32_t q = realise(m, p, log);
    if (!joined_edge(m, tip, q)) {  // the way runs along the rim or an opened cut
      r.reached_boundary = boundary;
      if (!boundary) r.stalled = true;
      break;
    }
    open_edge(m, tip, q, log);
    visited.push_back(tip);
    path.sources.push_back(q);
    path.tip = q;
    to_kind = p.kind;
    r.made = true;
    if (boundary) {
      r.reached_boundary = true;
      break;
    }
    if (arrives) break;
  }

  finish_segment(m, path, s, r, log, visited, start, {from_kind, to_kind, subsequent},
                 {touched_before, new_before});
  return r;
}

}  // namespace phaco::cut
