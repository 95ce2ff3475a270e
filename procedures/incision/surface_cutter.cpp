#include "procedures/incision/surface_cutter.hpp"

#include "systems/cut/cut_point.hpp"

namespace phaco::corneal_incision {

namespace {

// An end is fed when it lies further from the puncture than the last one fed by more than this
// (a blade resting fully in, or withdrawing, cuts nothing more).
constexpr double kWidenMm = 1e-9;

// Feeds `end` to a side's path if the cut widens there; true if the mesh changed.
bool feed(cut::CutMesh& m, SurfaceCutter& s, int side, const Vec3& end,
          const cut::CutSettings& settings, cut::EditLog& log, uint64_t& segments) {
  SidePath& p = s.side[side];
  if (p.path.reached_boundary) return false;
  const double d = (end - s.puncture).norm();
  if (d <= p.reach_mm + kWidenMm) return false;
  p.reach_mm = d;
  const cut::SegmentReport r = cut::cut_towards(m, p.path, end, settings, log);
  if (r.made) ++segments;
  return r.made;
}

}  // namespace

bool cut_surface(cut::CutMesh& m, SurfaceCutter& s, const incision::BladeSection& sec,
                 const cut::CutSettings& settings, cut::EditLog& log, uint64_t& segments) {
  if (!sec.touches) return false;
  SidePath& left = s.side[0];
  SidePath& right = s.side[1];
  if (!s.started) {
    if (!sec.has_puncture) return false;
    s.started = true;
    s.puncture = sec.puncture;
    // A walk from an arbitrary triangle could settle on the other cap of the closed shell (a
    // local minimum of the distance): start from the nearest triangle — the caller's start
    // triangle if it gave one (a grid lookup), else found by a scan of the whole mesh.
    left.path.hint_triangle = cut::locate_cut_point(m.particles, m.triangles, m.topology.adjacency,
                                                    s.start_triangle, s.puncture, settings.snap)
                                  .triangle;
    cut::cut_towards(m, left.path, s.puncture, settings, log);
  }
  bool made = feed(m, s, 0, sec.left, settings, log, segments);
  // The right path starts where the left one made the puncture a vertex, so both are one cut.
  if (!right.path.started && !left.path.sources.empty()) {
    const uint32_t c0 = left.path.sources.front();
    if (m.particles.slots.alive(c0)) {
      right.path.hint_triangle = m.topology.vertex_triangle[c0];
      cut::cut_towards(m, right.path, cut::particle_position(m.particles, c0), settings, log);
    }
  }
  if (right.path.started) made = feed(m, s, 1, sec.right, settings, log, segments) || made;
  return made;
}

bool finish_surface(cut::CutMesh& m, SurfaceCutter& s, const cut::CutSettings& settings,
                    double min_angle_deg, cut::EditLog& log, uint64_t& segments) {
  bool made = false;
  for (SidePath& p : s.side) {
    if (cut::finish_cut(m, p.path, settings, min_angle_deg, log)) ++segments, made = true;
  }
  return made;
}

uint32_t live_tip(const cut::CutMesh& m, const cut::CutPath& p) {
  return p.tip != kInvalidIndex && m.particles.slots.alive(p.tip) ? p.tip : kInvalidIndex;
}

std::vector<Vec3> tool_polyline(const SurfaceCutter& s) {
  std::vector<Vec3> out;
  if (!s.started) return out;
  const auto& l = s.side[0].path.tool_points;
  const auto& r = s.side[1].path.tool_points;
  for (size_t k = l.size(); k-- > 1;) out.push_back(l[k]);
  out.push_back(s.puncture);
  for (size_t k = 1; k < r.size(); ++k) out.push_back(r[k]);  // r[0] is the puncture's vertex
  return out;
}

}  // namespace phaco::corneal_incision
