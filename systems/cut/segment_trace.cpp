#include "systems/cut/segment_trace.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace phaco::cut {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kEndTol = 1e-12;         // exit parameter this close to 1 = the target itself
constexpr double kTraceStuckTol = 1e-12;  // exit parameter this close to 0 = no way forward

// Where the walk stands: a face point of one triangle, a point on an edge, or a vertex.
struct Location {
  CutPoint::Kind kind = CutPoint::Face;
  uint32_t triangle = kInvalidIndex;  // Face only
  Vec3 bary = Vec3::Zero();           // Face only
  uint32_t a = kInvalidIndex, b = kInvalidIndex;
  double t = 0.0;
  Vec3 position = Vec3::Zero();
};

// Barycentric weights of the location in triangle T (which holds it).
Vec3 bary_in(const Triangles& tr, const Location& l, uint32_t T) {
  Vec3 w = Vec3::Zero();
  if (l.kind == CutPoint::Face) return l.bary;
  if (l.kind == CutPoint::Vertex) {
    w[corner_slot(tr, T, l.a)] = 1.0;
  } else {
    w[corner_slot(tr, T, l.a)] = 1.0 - l.t;
    w[corner_slot(tr, T, l.b)] = l.t;
  }
  return w;
}

double chord_parameter(const Vec3& x, const CutPoint& from, const CutPoint& to) {
  const Vec3 c = to.position - from.position;
  const double len2 = c.squaredNorm();
  return len2 > 0 ? std::clamp((x - from.position).dot(c) / len2, 0.0, 1.0) : 0.0;
}

void check_point(const Triangles& tr, const CutPoint& c, const char* which) {
  if (!c.position.allFinite())
    throw std::invalid_argument(std::string("trace_segment: ") + which + " position is not finite");
  if (!tr.slots.alive(c.triangle))
    throw std::invalid_argument(std::string("trace_segment: ") + which +
                                " lies on a dead or out-of-range triangle (locate it again)");
}

}  // namespace

void trace_segment(const Particles& p, const Triangles& tr, const TriangleAdjacency& adj,
                   const CutPoint& from, const CutPoint& to, const SnapSettings& snap,
                   SegmentTrace& out) {
  out.clear();
  check_point(tr, from, "from");
  check_point(tr, to, "to");
  if (adj.neighbour.size() != tr.slots.size())
    throw std::invalid_argument("trace_segment: adjacency built for another triangle table");

  Location here;
  here.kind = from.kind;
  here.triangle = from.triangle;
  here.bary = from.bary;
  here.a = from.a;
  here.b = from.b;
  here.t = from.t;
  here.position = from.position;

  std::vector<uint32_t>& cand = out.scratch;
  const uint32_t budget = 2 * tr.slots.size() + 8;
  for (uint32_t step = 0; step < budget; ++step) {
    cand.clear();
    if (here.kind == CutPoint::Face) {
      cand.push_back(here.triangle);
    } else if (here.kind == CutPoint::Vertex) {
      vertex_fan(tr, adj, here.triangle, here.a, cand);
    } else {
      cand.push_back(here.triangle);
      const int k = [&] {
        for (int e = 0; e < 3; ++e) {
          const uint32_t u = corner(tr, here.triangle, e),
                         v = corner(tr, here.triangle, (e + 1) % 3);
          if ((u == here.a && v == here.b) || (u == here.b && v == here.a)) return e;
        }
        return -1;
      }();
      const uint32_t n = k >= 0 ? adj.neighbour[here.triangle][k] : kInvalidIndex;
      if (n != kInvalidIndex) cand.push_back(n);
      std::sort(cand.begin(), cand.end());
    }

    // The candidate the direction goes furthest into (lowest index on ties).
    uint32_t T = kInvalidIndex;
    double best_s = -1.0;
    int best_exit = -1;
    Vec3 best_from = Vec3::Zero(), best_target = Vec3::Zero();
    for (uint32_t c : cand) {
      if (to.kind == CutPoint::Face && c == to.triangle) {
        T = c, best_s = kInf, best_exit = -1;
        break;
      }
      Vec3 wt;
      if (!projected_bary(p, tr, c, to.position, wt)) continue;
      const Vec3 wf = bary_in(tr, here, c);
      int exit = -1;
      const double s = exit_parameter(wf, wt, exit);
      if (s > best_s) T = c, best_s = s, best_exit = exit, best_from = wf, best_target = wt;
    }
    if (T == kInvalidIndex || best_s <= kTraceStuckTol)
      return;  // e.g. heading off the rim at a vertex
    out.triangles.push_back(T);
    if (best_s >= 1.0 - kEndTol) {
      out.complete = true;
      return;
    }

    Vec3 w = best_from + best_s * (best_target - best_from);
    w[best_exit] = 0.0;
    w = w.cwiseMax(0.0);
    w /= w.sum();
    const Vec3 X[3] = {particle_position(p, tr.a[T]), particle_position(p, tr.b[T]),
                       particle_position(p, tr.c[T])};
    const Vec3 x = w[0] * X[0] + w[1] * X[1] + w[2] * X[2];

    // Proximity snap of the exit point to a corner (never back to the vertex we stand on).
    int snap_k = -1;
    double snap_d = kInf;
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = corner(tr, T, k);
      if (here.kind == CutPoint::Vertex && v == here.a) continue;
      const double d = (x - X[k]).norm();
      if ((d <= snap.vertex_snap_mm || w[k] >= 1.0 - kEndTol) && d < snap_d) snap_k = k, snap_d = d;
    }

    Crossing cr;
    if (snap_k >= 0) {
      const uint32_t v = corner(tr, T, snap_k);
      if (to.kind == CutPoint::Vertex && v == to.a) {
        out.complete = true;
        return;
      }
      cr.kind = Crossing::Vertex;
      cr.a = v;
      cr.position = X[snap_k];
      here.kind = CutPoint::Vertex;
      here.triangle = T;
      here.a = v;
      here.b = kInvalidIndex;
    } else {
      const int i1 = (best_exit + 1) % 3, i2 = (best_exit + 2) % 3;
      uint32_t a = corner(tr, T, i1), b = corner(tr, T, i2);
      double t = w[i2] / (w[i1] + w[i2]);
      if (a > b) std::swap(a, b), t = 1.0 - t;
      if (to.kind == CutPoint::Edge && a == to.a && b == to.b) {
        out.complete = true;
        return;
      }
      cr.kind = Crossing::Edge;
      cr.a = a;
      cr.b = b;
      cr.t = t;
      cr.position = x;
      const uint32_t n = adj.neighbour[T][i1];  // edge i1 joins corners i1 and i1+1 = i2
      here.kind = CutPoint::Edge;
      here.a = a;
      here.b = b;
      here.t = t;
      if (n == kInvalidIndex) {  // the segment leaves the mesh across the rim
        cr.s = chord_parameter(cr.position, from, to);
        out.crossings.push_back(cr);
        return;
      }
      here.triangle = n;
    }
    cr.s = chord_parameter(cr.position, from, to);
    here.position = cr.position;
    out.crossings.push_back(cr);
  }
}

SegmentTrace trace_segment(const Particles& p, const Triangles& tr, const TriangleAdjacency& adj,
                           const CutPoint& from, const CutPoint& to, const SnapSettings& snap) {
  SegmentTrace out;
  trace_segment(p, tr, adj, from, to, snap, out);
  return out;
}

}  // namespace phaco::cut
