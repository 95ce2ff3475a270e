#include "systems/topology_check/topology_check.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <numbers>

namespace phaco::topology_check {
namespace {

using HalfEdge = InvariantScratch::HalfEdge;
using SpringKey = InvariantScratch::SpringKey;

uint64_t edge_key(uint32_t a, uint32_t b) {
  return (static_cast<uint64_t>(std::min(a, b)) << 32) | std::max(a, b);
}
uint32_t key_lo(uint64_t key) {
  return static_cast<uint32_t>(key >> 32);
}
uint32_t key_hi(uint64_t key) {
  return static_cast<uint32_t>(key & 0xffffffffu);
}

// Records are built only on a violation, so formatting cost never touches a clean frame.
std::string format(const char* fmt, ...) {
  char buffer[256];
  va_list args;
  va_start(args, fmt);
  const int n = std::vsnprintf(buffer, sizeof buffer, fmt, args);
  va_end(args);
  return std::string(buffer,
                     static_cast<size_t>(std::clamp(n, 0, static_cast<int>(sizeof buffer) - 1)));
}

struct Recorder {
  InvariantReport& report;
  void add(Violation kind, ElementTable table, uint32_t element, uint32_t other,
           std::string detail) {
    report.violations.push_back({kind, element, other, std::move(detail), table});
  }
};

// Smallest index up to which every column of a table has data, reporting a short column.
template <class... Columns>
uint32_t usable_size(const SlotIndex& slots, ElementTable table, Recorder& rec,
                     const Columns&... columns) {
  const uint32_t slot_count = slots.size();
  const size_t shortest = std::min({columns.size()...});
  if (shortest >= slot_count) return slot_count;
  const auto usable = static_cast<uint32_t>(shortest);
  rec.add(Violation::IndexOutOfRange, table, usable, slot_count,
          format("%s table: a column has %u entries for %u slots", to_string(table).data(), usable,
                 slot_count));
  return usable;
}

uint32_t index_of(const HalfEdge& h) {
  return h.triangle;
}
uint32_t index_of(const SpringKey& k) {
  return k.spring;
}

// Sorts by (key, index) in O(n): counting sort on the lower particle (the key's high word), then
// a stable insertion sort of each bucket by the upper one (buckets hold a vertex's valence, about
// six). Plain loops, so the check stays cheap in unoptimised debug builds, where std::sort with a
// comparator cost ten times more. `items` must arrive in increasing index order; a bucket of
// more than 32 (a fan of that valence) falls back to std::sort, which does not allocate.
template <class T>
void sort_by_key(std::vector<T>& items, std::vector<T>& out, std::vector<uint32_t>& bucket,
                 uint32_t bucket_count) {
  bucket.assign(size_t{bucket_count} + 1, 0);
  uint32_t* offset = bucket.data();
  const T* in = items.data();
  const size_t n = items.size();
  for (size_t k = 0; k < n; ++k) ++offset[key_lo(in[k].key) + 1];
  for (uint32_t b = 0; b < bucket_count; ++b) offset[b + 1] += offset[b];
  out.resize(n);
  T* o = out.data();
  for (size_t k = 0; k < n; ++k) o[offset[key_lo(in[k].key)]++] = in[k];  // offset[b]: b's end
  uint32_t begin = 0;
  for (uint32_t b = 0; b < bucket_count; ++b) {
    const uint32_t end = offset[b];
    if (end - begin > 32) {
      std::sort(o + begin, o + end, [](const T& x, const T& y) {
        return x.key < y.key || (x.key == y.key && index_of(x) < index_of(y));
      });
    } else {
      for (uint32_t k = begin + 1; k < end; ++k) {
        const T it = o[k];
        uint32_t m = k;
        for (; m > begin && o[m - 1].key > it.key; --m) o[m] = o[m - 1];
        o[m] = it;
      }
    }
    begin = end;
  }
  items.swap(out);
}

// Union-find over triangle corners (3·t + k), path halving; the smaller index becomes the root so
// the sets, and the records naming them, do not depend on the order of the unions.
uint32_t find_set(uint32_t* parent, uint32_t x) {
  while (parent[x] != x) {
    parent[x] = parent[parent[x]];
    x = parent[x];
  }
  return x;
}
void unite_sets(uint32_t* parent, uint32_t a, uint32_t b) {
  a = find_set(parent, a);
  b = find_set(parent, b);
  if (a != b) parent[std::max(a, b)] = std::min(a, b);
}

// Corner of valid triangle t at particle q (q is one of its three).
uint32_t corner_of(const uint32_t* ta, const uint32_t* tb, uint32_t t, uint32_t q) {
  return 3 * t + (ta[t] == q ? 0u : tb[t] == q ? 1u : 2u);
}

bool finite3(float a, float b, float c) {
  return std::isfinite(a) && std::isfinite(b) && std::isfinite(c);
}

void check_particles(const Particles& p, uint32_t usable, Recorder& rec) {
  // Raw pointers in the loops of this file: debug builds (-O0) run the check every frame, and
  // there every operator[] is a call.
  const uint8_t* alive = p.slots.alive_mask().data();
  const float *x = p.x.data(), *y = p.y.data(), *z = p.z.data();
  const float *vx = p.vx.data(), *vy = p.vy.data(), *vz = p.vz.data();
  for (uint32_t i = 0; i < usable; ++i) {
    if (!alive[i]) continue;
    ++rec.report.checked_particles;
    const bool pos = finite3(x[i], y[i], z[i]);
    const bool vel = finite3(vx[i], vy[i], vz[i]);
    if (pos && vel) continue;
    rec.add(Violation::NonFinitePosition, ElementTable::Particle, i, kInvalidIndex,
            format("particle %u: position (%g, %g, %g), velocity (%g, %g, %g)", i, p.x[i], p.y[i],
                   p.z[i], p.vx[i], p.vy[i], p.vz[i]));
  }
}

// Area and angles in double from float positions. An angle at a corner with edge vectors u, v is
// below θ (< 90°) iff u·v > 0 and |u×v| < tan θ · u·v; |u×v| is twice the area at every corner,
// so no trigonometry runs unless a triangle fails.
void check_shape(const Particles& p, uint32_t t, const std::array<uint32_t, 3>& v,
                 const InvariantThresholds& th, double tan_min_angle, Recorder& rec) {
  std::array<std::array<double, 3>, 3> q;
  for (int k = 0; k < 3; ++k) q[k] = {p.x[v[k]], p.y[v[k]], p.z[v[k]]};
  auto sub = [](const std::array<double, 3>& a, const std::array<double, 3>& b) {
    return std::array<double, 3>{a[0] - b[0], a[1] - b[1], a[2] - b[2]};
  };
  auto dot = [](const std::array<double, 3>& a, const std::array<double, 3>& b) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  };
  const auto e01 = sub(q[1], q[0]);
  const auto e02 = sub(q[2], q[0]);
  const auto e12 = sub(q[2], q[1]);
  const double cx = e01[1] * e02[2] - e01[2] * e02[1];
  const double cy = e01[2] * e02[0] - e01[0] * e02[2];
  const double cz = e01[0] * e02[1] - e01[1] * e02[0];
  const double cross = std::sqrt(cx * cx + cy * cy + cz * cz);
  const double area = 0.5 * cross;
  if (!(area >= th.min_area_mm2)) {
    rec.add(Violation::SmallArea, ElementTable::Triangle, t, kInvalidIndex,
            format("triangle %u (%u, %u, %u): area %.3g mm^2 < %.3g", t, v[0], v[1], v[2], area,
                   th.min_area_mm2));
    return;
  }
  const std::array<double, 3> corner_dot = {dot(e01, e02), -dot(e01, e12), dot(e02, e12)};
  int worst = -1;
  double worst_angle = 0.0;
  for (int k = 0; k < 3; ++k) {
    if (corner_dot[k] > 0.0 && cross < tan_min_angle * corner_dot[k]) {
      const double angle = std::atan2(cross, corner_dot[k]);
      if (worst < 0 || angle < worst_angle) worst = k, worst_angle = angle;
    }
  }
  if (worst < 0) return;
  rec.add(Violation::SmallAngle, ElementTable::Triangle, t, v[worst],
          format("triangle %u (%u, %u, %u): angle %.3g deg at particle %u < %.3g", t, v[0], v[1],
                 v[2], worst_angle * 180.0 / std::numbers::pi, v[worst], th.min_angle_deg));
}

// Validates each alive triangle's indices and shape; pushes the half-edges of those whose three
// particles are alive and distinct.
void check_triangles(const Particles& p, uint32_t particle_usable, const Triangles& tri,
                     uint32_t usable, const InvariantThresholds& th, InvariantScratch& s,
                     Recorder& rec) {
  const double min_angle = std::clamp(th.min_angle_deg, 0.0, 89.999) * std::numbers::pi / 180.0;
  const double tan_min_angle = std::tan(min_angle);
  const uint8_t* alive = tri.slots.alive_mask().data();
  const uint8_t* particle_alive = p.slots.alive_mask().data();
  const uint32_t *ta = tri.a.data(), *tb = tri.b.data(), *tc = tri.c.data();
  const float *x = p.x.data(), *y = p.y.data(), *z = p.z.data();
  s.half_edges.resize(size_t{usable} * 3);
  s.valid.assign(usable, 0);
  HalfEdge* he = s.half_edges.data();
  size_t edge_count = 0;
  for (uint32_t t = 0; t < usable; ++t) {
    if (!alive[t]) continue;
    ++rec.report.checked_triangles;
    const std::array<uint32_t, 3> v = {ta[t], tb[t], tc[t]};
    bool referenced_ok = true;
    for (uint32_t q : v) {
      if (q >= particle_usable) {
        rec.add(Violation::IndexOutOfRange, ElementTable::Triangle, t, q,
                format("triangle %u (%u, %u, %u): particle %u out of range (%u)", t, v[0], v[1],
                       v[2], q, particle_usable));
        referenced_ok = false;
        break;
      }
    }
    if (!referenced_ok) continue;
    for (uint32_t q : v) {
      if (!particle_alive[q]) {
        rec.add(Violation::DeadParticleReferenced, ElementTable::Triangle, t, q,
                format("triangle %u (%u, %u, %u): particle %u is removed", t, v[0], v[1], v[2], q));
        referenced_ok = false;
        break;
      }
    }
    if (!referenced_ok) continue;
    if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) {
      const uint32_t repeated = (v[0] == v[1] || v[0] == v[2]) ? v[0] : v[1];
      rec.add(
          Violation::DegenerateTriangle, ElementTable::Triangle, t, repeated,
          format("triangle %u (%u, %u, %u): particle %u repeated", t, v[0], v[1], v[2], repeated));
      continue;
    }
    s.valid[t] = 1;
    for (int k = 0; k < 3; ++k) {
      const uint32_t u = v[k];
      const uint32_t w = v[(k + 1) % 3];
      he[edge_count++] = {edge_key(u, w), t, u < w ? 1u : 0u};
    }
    bool finite = true;
    for (uint32_t q : v) finite = finite && finite3(x[q], y[q], z[q]);
    if (finite) check_shape(p, t, v, th, tan_min_angle, rec);  // a NaN is reported per particle
  }
  s.half_edges.resize(edge_count);
}

// One walk over the sorted half-edges: distinct edges, non-manifold edges, orientation; and the
// corners of the triangles sharing an edge joined at both its ends (check_vertices counts them).
void check_edges(const Triangles& tri, uint32_t particle_usable, uint32_t triangle_usable,
                 InvariantScratch& s, Recorder& rec) {
  sort_by_key(s.half_edges, s.sorted_half_edges, s.bucket, particle_usable);
  s.interior_count.assign(triangle_usable, 0);
  s.bad_count.assign(triangle_usable, 0);
  s.corner_set.resize(size_t{triangle_usable} * 3);
  uint32_t* corner_set = s.corner_set.data();
  for (uint32_t c = 0; c < 3 * triangle_usable; ++c) corner_set[c] = c;
  const uint32_t *ta = tri.a.data(), *tb = tri.b.data();
  const HalfEdge* he = s.half_edges.data();
  const size_t n = s.half_edges.size();
  uint8_t* interior_count = s.interior_count.data();
  for (size_t i = 0; i < n;) {
    size_t j = i + 1;
    while (j < n && he[j].key == he[i].key) ++j;
    const size_t uses = j - i;
    s.edges.push_back(he[i]);
    // Joined across an edge of more than two triangles too: that edge is its own record, and
    // the vertex check then names only fans that touch at the vertex and nowhere else.
    const uint32_t lo = key_lo(he[i].key), hi = key_hi(he[i].key);
    for (size_t k = i + 1; k < j; ++k) {
      unite_sets(corner_set, corner_of(ta, tb, he[i].triangle, lo),
                 corner_of(ta, tb, he[k].triangle, lo));
      unite_sets(corner_set, corner_of(ta, tb, he[i].triangle, hi),
                 corner_of(ta, tb, he[k].triangle, hi));
    }
    if (uses > 2) {
      rec.add(Violation::EdgeWithMoreThanTwoTriangles, ElementTable::Triangle, he[j - 1].triangle,
              he[i].triangle,
              format("edge (%u, %u) has %zu triangles, first %u, last %u", key_lo(he[i].key),
                     key_hi(he[i].key), uses, he[i].triangle, he[j - 1].triangle));
    } else if (uses == 2) {
      const uint32_t t0 = he[i].triangle;
      const uint32_t t1 = he[i + 1].triangle;
      ++interior_count[t0];
      ++interior_count[t1];
      if (he[i].forward == he[i + 1].forward) {
        ++s.bad_count[t0];
        ++s.bad_count[t1];
        s.inconsistent.push_back({t0, t1});
      }
    }
    i = j;
  }
  if (s.inconsistent.empty()) return;

  // Blame, across each same-direction edge, the triangle with the larger share of such edges
  // (ties: the higher index), so a single flipped triangle is reported once, not once per
  // neighbour.
  s.blamed.assign(triangle_usable, 0);
  auto blamed_of = [&](const InvariantScratch::Pair& pr) {
    const uint32_t b0 = s.bad_count[pr.t0], n0 = s.interior_count[pr.t0];
    const uint32_t b1 = s.bad_count[pr.t1], n1 = s.interior_count[pr.t1];
    return b0 * n1 > b1 * n0 ? pr.t0 : pr.t1;  // pr.t0 < pr.t1
  };
  for (const auto& pr : s.inconsistent) {
    const uint32_t t = blamed_of(pr);
    if (s.blamed[t]) continue;
    s.blamed[t] = 1;
    const uint32_t other = t == pr.t0 ? pr.t1 : pr.t0;
    rec.add(Violation::InconsistentOrientation, ElementTable::Triangle, t, other,
            format("triangle %u runs %u of its %u shared edges the same way as its neighbour "
                   "(e.g. triangle %u)",
                   t, unsigned{s.bad_count[t]}, unsigned{s.interior_count[t]}, other));
  }
}

// Fans per particle: the corner sets whose root lies at it. A particle with two or more is a
// bowtie; its record names its lowest-index triangle's fan and a triangle outside it.
void check_vertices(const Triangles& tri, uint32_t particle_usable, uint32_t triangle_usable,
                    InvariantScratch& s, Recorder& rec) {
  s.fans.assign(particle_usable, 0);
  uint32_t* fans = s.fans.data();
  uint32_t* corner_set = s.corner_set.data();
  const uint8_t* valid = s.valid.data();
  const std::array<const uint32_t*, 3> corner = {tri.a.data(), tri.b.data(), tri.c.data()};
  bool any = false;
  for (uint32_t t = 0; t < triangle_usable; ++t) {
    if (!valid[t]) continue;
    for (uint32_t k = 0; k < 3; ++k) {
      if (find_set(corner_set, 3 * t + k) != 3 * t + k) continue;
      any = any || fans[corner[k][t]] > 0;
      ++fans[corner[k][t]];
    }
  }
  if (!any) return;
  // Only on a violation: per particle, the first fan's root (its lowest corner) and whether the
  // particle has been reported.
  std::vector<uint32_t> first_fan(particle_usable, kInvalidIndex);
  for (uint32_t t = 0; t < triangle_usable; ++t) {
    if (!valid[t]) continue;
    for (uint32_t k = 0; k < 3; ++k) {
      const uint32_t q = corner[k][t];
      if (fans[q] < 2) continue;
      const uint32_t root = find_set(corner_set, 3 * t + k);
      if (first_fan[q] == kInvalidIndex) {
        first_fan[q] = root;
      } else if (root != first_fan[q]) {
        rec.add(Violation::NonManifoldVertex, ElementTable::Particle, q, t,
                format("particle %u: its triangles form %u fans touching only at it (triangle %u "
                       "and triangle %u are in different fans)",
                       q, fans[q], first_fan[q] / 3, t));
        fans[q] = 0;  // reported once
      }
    }
  }
}

void check_springs(const Particles& p, uint32_t particle_usable, const Springs& sp, uint32_t usable,
                   InvariantScratch& s, Recorder& rec) {
  const uint8_t* alive = sp.slots.alive_mask().data();
  const uint8_t* particle_alive = p.slots.alive_mask().data();
  const uint32_t *si = sp.i.data(), *sj = sp.j.data();
  const float *rest_length = sp.rest_length.data(), *stiffness = sp.stiffness.data();
  s.spring_keys.resize(usable);
  SpringKey* keys_out = s.spring_keys.data();
  size_t key_count = 0;
  for (uint32_t e = 0; e < usable; ++e) {
    if (!alive[e]) continue;
    ++rec.report.checked_springs;
    const uint32_t i = si[e];
    const uint32_t j = sj[e];
    if (i >= particle_usable || j >= particle_usable) {
      const uint32_t bad = i >= particle_usable ? i : j;
      rec.add(Violation::IndexOutOfRange, ElementTable::Spring, e, bad,
              format("spring %u (%u, %u): particle %u out of range (%u)", e, i, j, bad,
                     particle_usable));
      continue;
    }
    if (!particle_alive[i] || !particle_alive[j]) {
      const uint32_t dead = !particle_alive[i] ? i : j;
      rec.add(Violation::DeadParticleReferenced, ElementTable::Spring, e, dead,
              format("spring %u (%u, %u): particle %u is removed", e, i, j, dead));
      continue;
    }
    const float rest = rest_length[e];
    const float k = stiffness[e];
    if (!(std::isfinite(rest) && std::isfinite(k) && rest >= 0.0f && k >= 0.0f)) {
      rec.add(Violation::NonFiniteSpring, ElementTable::Spring, e, kInvalidIndex,
              format("spring %u (%u, %u): rest length %g, stiffness %g", e, i, j, rest, k));
    }
    if (i >= j) {
      rec.add(Violation::SpringIndexOrder, ElementTable::Spring, e, kInvalidIndex,
              format("spring %u (%u, %u): i >= j", e, i, j));
    }
    keys_out[key_count++] = {edge_key(i, j), e};
  }
  s.spring_keys.resize(key_count);
  sort_by_key(s.spring_keys, s.sorted_spring_keys, s.bucket, particle_usable);

  // Merge the sorted distinct edges against the sorted spring pairs.
  const auto& edges = s.edges;
  const auto& keys = s.spring_keys;
  size_t a = 0;
  size_t b = 0;
  while (a < edges.size() || b < keys.size()) {
    if (b < keys.size() && b > 0 && keys[b].key == keys[b - 1].key) {
      size_t first = b - 1;
      while (first > 0 && keys[first - 1].key == keys[b].key) --first;
      rec.add(Violation::DuplicateSpring, ElementTable::Spring, keys[b].spring, keys[first].spring,
              format("springs %u and %u both join (%u, %u)", keys[first].spring, keys[b].spring,
                     key_lo(keys[b].key), key_hi(keys[b].key)));
      ++b;
    } else if (b == keys.size() || (a < edges.size() && edges[a].key < keys[b].key)) {
      rec.add(Violation::EdgeWithoutSpring, ElementTable::Triangle, edges[a].triangle,
              kInvalidIndex,
              format("edge (%u, %u) of triangle %u has no spring", key_lo(edges[a].key),
                     key_hi(edges[a].key), edges[a].triangle));
      ++a;
    } else if (a == edges.size() || keys[b].key < edges[a].key) {
      rec.add(Violation::SpringWithoutEdge, ElementTable::Spring, keys[b].spring, kInvalidIndex,
              format("spring %u (%u, %u) is on no triangle", keys[b].spring, sp.i[keys[b].spring],
                     sp.j[keys[b].spring]));
      ++b;
    } else {
      ++a;
      ++b;
    }
  }
}

}  // namespace

std::string_view to_string(Violation v) {
  switch (v) {
    case Violation::IndexOutOfRange:
      return "IndexOutOfRange";
    case Violation::DeadParticleReferenced:
      return "DeadParticleReferenced";
    case Violation::NonFinitePosition:
      return "NonFinitePosition";
    case Violation::DegenerateTriangle:
      return "DegenerateTriangle";
    case Violation::EdgeWithMoreThanTwoTriangles:
      return "EdgeWithMoreThanTwoTriangles";
    case Violation::InconsistentOrientation:
      return "InconsistentOrientation";
    case Violation::SmallArea:
      return "SmallArea";
    case Violation::SmallAngle:
      return "SmallAngle";
    case Violation::SpringWithoutEdge:
      return "SpringWithoutEdge";
    case Violation::EdgeWithoutSpring:
      return "EdgeWithoutSpring";
    case Violation::DuplicateSpring:
      return "DuplicateSpring";
    case Violation::SpringIndexOrder:
      return "SpringIndexOrder";
    case Violation::NonFiniteSpring:
      return "NonFiniteSpring";
    case Violation::NonManifoldVertex:
      return "NonManifoldVertex";
  }
  return "Unknown";
}

std::string_view to_string(ElementTable t) {
  switch (t) {
    case ElementTable::Particle:
      return "particle";
    case ElementTable::Triangle:
      return "triangle";
    case ElementTable::Spring:
      return "spring";
  }
  return "unknown";
}

size_t InvariantReport::count(Violation v) const {
  return static_cast<size_t>(std::count_if(violations.begin(), violations.end(),
                                           [v](const ViolationRecord& r) { return r.kind == v; }));
}

std::string InvariantReport::summary(size_t max_lines) const {
  std::string out = format("%zu violation%s (checked %zu particles, %zu triangles, %zu springs)",
                           violations.size(), violations.size() == 1 ? "" : "s", checked_particles,
                           checked_triangles, checked_springs);
  const char* sep = ": ";
  for (int k = 0; k < kViolationKinds; ++k) {
    const auto kind = static_cast<Violation>(k);
    const size_t n = count(kind);
    if (n == 0) continue;
    out += sep;
    out += std::to_string(n);
    out += ' ';
    out += to_string(kind);
    sep = ", ";
  }
  const size_t shown = std::min(max_lines, violations.size());
  for (size_t r = 0; r < shown; ++r) {
    out += "\n  ";
    out += to_string(violations[r].kind);
    out += ": ";
    out += violations[r].detail;
  }
  if (shown < violations.size()) out += format("\n  ... and %zu more", violations.size() - shown);
  return out;
}

InvariantReport check_membrane(const Particles& particles, const Triangles& triangles,
                               const Springs& springs, const InvariantThresholds& thresholds,
                               InvariantScratch& scratch) {
  InvariantReport report;
  Recorder rec{report};
  scratch.half_edges.clear();
  scratch.spring_keys.clear();
  scratch.edges.clear();
  scratch.inconsistent.clear();

  const Particles& p = particles;
  const uint32_t np =
      usable_size(p.slots, ElementTable::Particle, rec, p.x, p.y, p.z, p.vx, p.vy, p.vz);
  const uint32_t nt = usable_size(triangles.slots, ElementTable::Triangle, rec, triangles.a,
                                  triangles.b, triangles.c);
  const uint32_t ns = usable_size(springs.slots, ElementTable::Spring, rec, springs.i, springs.j,
                                  springs.rest_length, springs.stiffness);
  check_particles(p, np, rec);
  check_triangles(p, np, triangles, nt, thresholds, scratch, rec);
  check_edges(triangles, np, nt, scratch, rec);
  check_vertices(triangles, np, nt, scratch, rec);
  check_springs(p, np, springs, ns, scratch, rec);
  return report;
}

InvariantReport check_membrane(const Particles& particles, const Triangles& triangles,
                               const Springs& springs, const InvariantThresholds& thresholds) {
  InvariantScratch scratch;
  return check_membrane(particles, triangles, springs, thresholds, scratch);
}

std::string check_spring_structure(const Springs& s, const SpringBlocks& blocks,
                                   const SpringGraph& g, uint32_t particle_count) {
  const uint32_t ns = s.slots.size(), nb = blocks.count();
  if (blocks.spring_begin.size() != blocks.particle_begin.size())
    return "blocks: spring and particle ranges differ in count";
  if (nb > 0 && blocks.spring_begin.front() != 0)
    return "blocks: the first block does not start at spring 0";
  for (uint32_t b = 0; b < nb; ++b)
    if (blocks.spring_begin[b] > blocks.spring_begin[b + 1] ||
        blocks.particle_begin[b] > blocks.particle_begin[b + 1])
      return format("blocks: block %u's range runs backwards", b);
  if (blocks.tail_begin() > ns)
    return format("blocks: tail starts at %u beyond %u springs", blocks.tail_begin(), ns);
  for (uint32_t b = 0; b < nb && nb > 2; ++b) {
    const uint32_t lo = blocks.particle_begin[b], hi = blocks.particle_begin[std::min(b + 2, nb)];
    for (uint32_t e = blocks.spring_begin[b]; e < blocks.spring_begin[b + 1]; ++e) {
      if (s.i[e] < lo || s.i[e] >= blocks.particle_begin[b + 1] || s.j[e] >= hi)
        return format("blocks: spring %u (%u, %u) lies outside block %u and the next", e, s.i[e],
                      s.j[e], b);
    }
  }
  for (uint32_t e = 0; e < ns; ++e)
    if (!s.slots.alive(e) && s.stiffness[e] != 0.0f)
      return format("spring %u is removed but pulls", e);

  if (g.particle_count() != particle_count)
    return format("graph: %u rows for %u particles", g.particle_count(), particle_count);
  std::vector<std::vector<std::pair<uint32_t, uint32_t>>> fresh(particle_count);
  for (uint32_t e = 0; e < ns; ++e) {
    if (!s.slots.alive(e)) continue;
    if (s.i[e] >= particle_count || s.j[e] >= particle_count)
      return format("spring %u (%u, %u) names a particle beyond %u", e, s.i[e], s.j[e],
                    particle_count);
    fresh[s.i[e]].emplace_back(s.j[e], e);
    fresh[s.j[e]].emplace_back(s.i[e], e);
  }
  std::vector<std::pair<uint32_t, uint32_t>> row;
  for (uint32_t p = 0; p < particle_count; ++p) {
    if (g.row_size[p] > g.row_capacity[p] ||
        size_t{g.row_begin[p]} + g.row_capacity[p] > g.neighbour.size())
      return format("graph: row %u overruns its room", p);
    row.clear();
    for (uint32_t k = g.begin(p); k < g.end(p); ++k) {
      if (k > g.begin(p) && g.neighbour[k] < g.neighbour[k - 1])
        return format("graph: row %u is not sorted", p);
      row.emplace_back(g.neighbour[k], g.spring[k]);
    }
    std::sort(row.begin(), row.end());
    std::sort(fresh[p].begin(), fresh[p].end());
    if (row != fresh[p])
      return format("graph: row %u has %zu entries, a fresh build %zu (or other ones)", p,
                    row.size(), fresh[p].size());
  }
  return "";
}

}  // namespace phaco::topology_check
