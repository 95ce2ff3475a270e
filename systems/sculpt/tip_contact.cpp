#include "systems/sculpt/tip_contact.hpp"

#include <ccd/ccd.h>

namespace phaco::sculpt {

const char* to_string(Narrowphase narrowphase) {
  switch (narrowphase) {
    case Narrowphase::CentreInSphere:
      return "centre";
    case Narrowphase::ExactGjk:
      return "gjk";
    case Narrowphase::ExactMpr:
      return "mpr";
  }
  return "?";
}

namespace {

struct TetShape {
  Vec3 v[4];
  Vec3 centre;
};

void tet_support(const void* obj, const ccd_vec3_t* dir, ccd_vec3_t* out) {
  const auto& s = *static_cast<const TetShape*>(obj);
  const Vec3 d(dir->v[0], dir->v[1], dir->v[2]);
  int best = 0;
  double best_dot = s.v[0].dot(d);
  for (int i = 1; i < 4; ++i) {
    const double dot = s.v[i].dot(d);
    if (dot > best_dot) best_dot = dot, best = i;
  }
  ccdVec3Set(out, s.v[best].x(), s.v[best].y(), s.v[best].z());
}

void tet_centre_fn(const void* obj, ccd_vec3_t* c) {
  const auto& s = *static_cast<const TetShape*>(obj);
  ccdVec3Set(c, s.centre.x(), s.centre.y(), s.centre.z());
}

void capsule_support(const void* obj, const ccd_vec3_t* dir, ccd_vec3_t* out) {
  const auto& c = *static_cast<const TipCapsule*>(obj);
  const Vec3 d(dir->v[0], dir->v[1], dir->v[2]);
  const Vec3& end = c.a.dot(d) > c.b.dot(d) ? c.a : c.b;
  const double len = d.norm();
  const Vec3 p = len > 0.0 ? Vec3(end + (c.radius / len) * d) : end;
  ccdVec3Set(out, p.x(), p.y(), p.z());
}

void capsule_centre_fn(const void* obj, ccd_vec3_t* out) {
  const auto& c = *static_cast<const TipCapsule*>(obj);
  const Vec3 m = 0.5 * (c.a + c.b);
  ccdVec3Set(out, m.x(), m.y(), m.z());
}

}  // namespace

bool tet_touches_tip(std::span<const Vec3> positions, const std::array<uint32_t, 4>& tet,
                     const TipCapsule& tip, Narrowphase method) {
  TetShape shape;
  for (int i = 0; i < 4; ++i) shape.v[i] = positions[tet[i]];
  shape.centre = 0.25 * (shape.v[0] + shape.v[1] + shape.v[2] + shape.v[3]);
  ccd_t ccd;
  CCD_INIT(&ccd);
  ccd.support1 = tet_support;
  ccd.support2 = capsule_support;
  ccd.center1 = tet_centre_fn;
  ccd.center2 = capsule_centre_fn;
  ccd.max_iterations = 100;
  ccd.mpr_tolerance = 1e-9;
  if (method == Narrowphase::ExactMpr) return ccdMPRIntersect(&shape, &tip, &ccd) != 0;
  return ccdGJKIntersect(&shape, &tip, &ccd) != 0;
}

}  // namespace phaco::sculpt
