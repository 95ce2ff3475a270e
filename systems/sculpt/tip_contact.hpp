#pragma once
// Phaco tip against one tet: the narrowphases of the sculpting step (seed 000 §5.3).
//
// The tip this step is the capsule swept by its sphere (radius r) from the previous to the current
// centre; with no motion it is the seed's bounding sphere.
//  - CentreInSphere: the seed's test, "the distance between the centre of a tetrahedron and the
//    tip ... less than the radius of the bounding sphere" (here: distance to the swept segment).
//  - ExactGjk / ExactMpr: tip capsule against the tet's convex hull by libccd (support functions
//    of both shapes). A tet whose centre passes the centre test is accepted without calling libccd,
//    so the exact tests remove a superset of the centre test by construction.
// Reads tet vertices and centres. Writes nothing.
#include <array>
#include <cstdint>
#include <span>

#include "components/tet_topology.hpp"
#include "engine/core/math.hpp"

namespace phaco::sculpt {

enum class Narrowphase { CentreInSphere, ExactGjk, ExactMpr };
const char* to_string(Narrowphase narrowphase);

// The swept tip of one step, in the lens frame (mm).
struct TipCapsule {
  Vec3 a = Vec3::Zero();  // previous centre
  Vec3 b = Vec3::Zero();  // current centre
  double radius = 0.0;
};

// Squared distance from p to segment [a, b].
inline double segment_distance2(const Vec3& a, const Vec3& b, const Vec3& p) {
  const Vec3 ab = b - a;
  const double len2 = ab.squaredNorm();
  double s = len2 > 0.0 ? (p - a).dot(ab) / len2 : 0.0;
  s = s < 0.0 ? 0.0 : (s > 1.0 ? 1.0 : s);
  return (a + s * ab - p).squaredNorm();
}

inline Vec3 tet_centre(const TetTopology& topo, uint32_t t) {
  return {topo.centre_x[t], topo.centre_y[t], topo.centre_z[t]};
}

// Seed's test: the tet's centre lies within the swept sphere.
inline bool centre_in_tip(const TetTopology& topo, uint32_t t, const TipCapsule& tip) {
  return segment_distance2(tip.a, tip.b, tet_centre(topo, t)) < tip.radius * tip.radius;
}

// Conservative: the tet's bounding sphere touches the tip (never false when the tet does).
inline bool bound_touches_tip(const TetTopology& topo, uint32_t t, const TipCapsule& tip) {
  const double reach = tip.radius + topo.bound_radius[t];
  return segment_distance2(tip.a, tip.b, tet_centre(topo, t)) <= reach * reach;
}

// Exact convex test of the tip capsule against tet t's hull (GJK or MPR, libccd).
bool tet_touches_tip(std::span<const Vec3> positions, const std::array<uint32_t, 4>& tet,
                     const TipCapsule& tip, Narrowphase method);

// The narrowphase decision: centre test, or centre test OR exact test.
inline bool narrowphase_hit(const TetTopology& topo, std::span<const Vec3> positions, uint32_t t,
                            const TipCapsule& tip, Narrowphase method) {
  if (centre_in_tip(topo, t, tip)) return true;
  if (method == Narrowphase::CentreInSphere) return false;
  return tet_touches_tip(positions, topo.vertices[t], tip, method);
}

}  // namespace phaco::sculpt
