#include "procedures/eye/revolve.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "engine/core/mesh_checks.hpp"

namespace phaco::eye {
namespace {

// Chords per curve for the arc-length table: the chord sum underestimates the arc by O(Δt²·κ²),
// far below 1e-6 mm for eye-sized curves, and inversion stays a binary search.
constexpr int kArcTableSegments = 8192;

double vertex_angle(const Ring& ring, uint32_t i) {
  return ring.phase + 2.0 * std::numbers::pi * static_cast<double>(i) / ring.count;
}

}  // namespace

MeridianCurve::MeridianCurve(std::function<RZ(double)> point, double t0, double t1)
    : point_(std::move(point)), t0_(t0), t1_(t1) {
  arc_.resize(kArcTableSegments + 1);
  arc_[0] = 0.0;
  RZ prev = point_(t0_);
  for (int i = 1; i <= kArcTableSegments; ++i) {
    const double t = i == kArcTableSegments ? t1_ : t0_ + (t1_ - t0_) * i / kArcTableSegments;
    const RZ cur = point_(t);
    const double chord = std::hypot(cur.r - prev.r, cur.z - prev.z);
    arc_[i] = arc_[i - 1] + chord;
    area_ += std::numbers::pi * (cur.r + prev.r) * chord;
    prev = cur;
  }
}

double MeridianCurve::param_at(double s) const {
  if (s <= 0.0) return t0_;
  if (s >= arc_.back()) return t1_;
  const auto it = std::upper_bound(arc_.begin(), arc_.end(), s);
  const auto i = static_cast<size_t>(it - arc_.begin()) - 1;
  const double span = arc_[i + 1] - arc_[i];
  const double f = span > 0.0 ? (s - arc_[i]) / span : 0.0;
  return t0_ + (t1_ - t0_) * (static_cast<double>(i) + f) / kArcTableSegments;
}

std::vector<RZ> profile_rings(const std::vector<MeridianCurve>& curves, double spacing) {
  std::vector<RZ> rings;
  for (size_t c = 0; c < curves.size(); ++c) {
    const MeridianCurve& curve = curves[c];
    const int steps = std::max(1, static_cast<int>(std::lround(curve.length() / spacing)));
    for (int k = c == 0 ? 0 : 1; k <= steps; ++k) {
      rings.push_back(curve.point_at_arc(curve.length() * k / steps));
    }
  }
  return rings;
}

void add_ring(SurfaceMesh& mesh, Ring& ring) {
  ring.first = static_cast<uint32_t>(mesh.vertices.size());
  if (ring.count == 1) {
    mesh.vertices.emplace_back(0.0, 0.0, ring.at.z);
    return;
  }
  for (uint32_t j = 0; j < ring.count; ++j) {
    const double phi = vertex_angle(ring, j);
    mesh.vertices.emplace_back(ring.at.r * std::cos(phi), ring.at.r * std::sin(phi), ring.at.z);
  }
}

void join_rings(SurfaceMesh& mesh, const Ring& a, const Ring& b) {
  // A pole never advances: advancing it would emit a triangle with a repeated vertex.
  const uint32_t steps_a = a.count == 1 ? 0 : a.count;
  const uint32_t steps_b = b.count == 1 ? 0 : b.count;
  const auto va = [&](uint32_t i) { return a.first + i % a.count; };
  const auto vb = [&](uint32_t j) { return b.first + j % b.count; };
  uint32_t i = 0, j = 0;
  while (i < steps_a || j < steps_b) {
    const double next_a =
        i < steps_a ? vertex_angle(a, i + 1) : std::numeric_limits<double>::infinity();
    const double next_b =
        j < steps_b ? vertex_angle(b, j + 1) : std::numeric_limits<double>::infinity();
    if (next_a <= next_b) {
      mesh.triangles.push_back({va(i), vb(j), va(i + 1)});
      ++i;
    } else {
      mesh.triangles.push_back({va(i), vb(j), vb(j + 1)});
      ++j;
    }
  }
}

uint32_t ring_vertex_count(double r, double ring_spacing, uint32_t min_count) {
  if (r <= 1e-9) return 1;
  const double edge = ring_spacing * 2.0 / std::sqrt(3.0);
  const auto n = static_cast<uint32_t>(std::lround(2.0 * std::numbers::pi * r / edge));
  return std::max(min_count, n);
}

SurfaceMesh revolve(const std::vector<RZ>& rings, double ring_spacing, uint32_t min_count) {
  SurfaceMesh mesh;
  std::vector<Ring> made;
  made.reserve(rings.size());
  for (size_t k = 0; k < rings.size(); ++k) {
    Ring ring{rings[k], ring_vertex_count(rings[k].r, ring_spacing, min_count), 0.0};
    // Odd rings turn by half a step so strips between equal rings form near-equilateral triangles.
    if (ring.count > 1 && k % 2 == 1) ring.phase = std::numbers::pi / ring.count;
    add_ring(mesh, ring);
    if (!made.empty()) join_rings(mesh, made.back(), ring);
    made.push_back(ring);
  }
  return mesh;
}

void flip(SurfaceMesh& mesh) {
  for (auto& t : mesh.triangles) std::swap(t[1], t[2]);
}

void orient_outward(SurfaceMesh& mesh) {
  if (signed_volume(mesh) < 0.0) flip(mesh);
}

void orient_toward_plus_z(SurfaceMesh& mesh) {
  double nz = 0.0;
  for (const auto& t : mesh.triangles) {
    const Vec3& a = mesh.vertices[t[0]];
    nz += (mesh.vertices[t[1]] - a).cross(mesh.vertices[t[2]] - a).z();
  }
  if (nz < 0.0) flip(mesh);
}

}  // namespace phaco::eye
