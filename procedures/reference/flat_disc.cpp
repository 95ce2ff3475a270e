#include "procedures/reference/flat_disc.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <set>
#include <stdexcept>
#include <utility>

#include "engine/core/rng.hpp"
#include "procedures/eye/revolve.hpp"

namespace phaco::reference {
namespace {

constexpr uint32_t kFirstRingSpokes = 8;
constexpr double kIrregularJitter = 0.3;  // of the ring spacing
constexpr int kMaxRings = 2048;

std::vector<eye::RZ> flat_rings(double radius, int count) {
  std::vector<eye::RZ> rings;
  for (int k = 0; k <= count; ++k) rings.push_back({radius * k / count, 0.0});
  return rings;
}

std::vector<uint32_t> curvilinear_counts(const std::vector<eye::RZ>& rings, double spacing) {
  std::vector<uint32_t> counts(rings.size(), 1);
  for (size_t k = 1; k < rings.size(); ++k) {
    counts[k] = k == 1 ? kFirstRingSpokes : counts[k - 1];
    if (k > 1 && 2.0 * std::numbers::pi * rings[k].r / counts[k] > 2.0 * spacing) counts[k] *= 2;
  }
  return counts;
}

std::vector<uint32_t> isotropic_counts(const std::vector<eye::RZ>& rings, double spacing) {
  std::vector<uint32_t> counts;
  for (const eye::RZ& rz : rings) counts.push_back(eye::ring_vertex_count(rz.r, spacing, 3));
  return counts;
}

uint64_t total(const std::vector<uint32_t>& v) {
  uint64_t s = 0;
  for (uint32_t c : v) s += c;
  return s;
}

// Same stitching as the capsule's curvilinear layout (see procedures/eye/capsule.cpp).
SurfaceMesh build_curvilinear(const std::vector<eye::RZ>& rings, double spacing) {
  const auto counts = curvilinear_counts(rings, spacing);
  SurfaceMesh mesh;
  std::vector<eye::Ring> made(rings.size());
  for (size_t k = 0; k < rings.size(); ++k) {
    made[k] = eye::Ring{rings[k], counts[k], 0.0};
    eye::add_ring(mesh, made[k]);
  }
  for (size_t k = 1; k < rings.size(); ++k) {
    const eye::Ring& in = made[k - 1];
    const eye::Ring& out = made[k];
    const auto iv = [&](uint32_t j) { return in.first + j % in.count; };
    const auto ov = [&](uint32_t j) { return out.first + j % out.count; };
    if (in.count == 1) {
      eye::join_rings(mesh, in, out);
    } else if (out.count == in.count) {
      for (uint32_t j = 0; j < in.count; ++j) {
        if ((k - 1 + j) % 2 == 0) {
          mesh.triangles.push_back({iv(j), ov(j), ov(j + 1)});
          mesh.triangles.push_back({iv(j), ov(j + 1), iv(j + 1)});
        } else {
          mesh.triangles.push_back({iv(j), ov(j), iv(j + 1)});
          mesh.triangles.push_back({iv(j + 1), ov(j), ov(j + 1)});
        }
      }
    } else {
      for (uint32_t j = 0; j < in.count; ++j) {
        mesh.triangles.push_back({iv(j), ov(2 * j), ov(2 * j + 1)});
        mesh.triangles.push_back({iv(j), ov(2 * j + 1), iv(j + 1)});
        mesh.triangles.push_back({iv(j + 1), ov(2 * j + 1), ov(2 * j + 2)});
      }
    }
  }
  return mesh;
}

double signed_area(const SurfaceMesh& m, const std::array<uint32_t, 3>& t) {
  const Vec3 &a = m.vertices[t[0]], &b = m.vertices[t[1]], &c = m.vertices[t[2]];
  return 0.5 * ((b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x()));
}

}  // namespace

const char* to_string(DiscLayout layout) {
  switch (layout) {
    case DiscLayout::Curvilinear:
      return "curvilinear";
    case DiscLayout::Isotropic:
      return "isotropic";
    case DiscLayout::Irregular:
      return "irregular";
  }
  return "unknown";
}

FlatDisc make_flat_disc(double radius, uint32_t target, DiscLayout layout, uint64_t seed) {
  if (!(radius > 0.0) || target < 4)
    throw std::invalid_argument("make_flat_disc: radius > 0, target ≥ 4");
  const bool curvilinear = layout == DiscLayout::Curvilinear;
  int best = 1;
  int64_t best_err = -1;
  for (int k = 1; k <= kMaxRings; ++k) {
    const auto rings = flat_rings(radius, k);
    const double spacing = radius / k;
    const auto n = static_cast<int64_t>(
        total(curvilinear ? curvilinear_counts(rings, spacing) : isotropic_counts(rings, spacing)));
    const int64_t err = std::llabs(n - static_cast<int64_t>(target));
    if (best_err < 0 || err < best_err) best = k, best_err = err;
    if (n > static_cast<int64_t>(target)) break;
  }
  FlatDisc disc;
  disc.radius_mm = radius;
  disc.rings = best;
  disc.ring_spacing_mm = radius / best;
  const auto rings = flat_rings(radius, best);
  disc.mesh = curvilinear ? build_curvilinear(rings, disc.ring_spacing_mm)
                          : eye::revolve(rings, disc.ring_spacing_mm);
  eye::orient_toward_plus_z(disc.mesh);
  disc.rim.assign(disc.mesh.vertices.size(), 0);
  for (size_t v = 0; v < disc.mesh.vertices.size(); ++v)
    if (disc.mesh.vertices[v].head<2>().norm() > radius - 1e-9 * radius) disc.rim[v] = 1;

  if (layout == DiscLayout::Irregular) {
    const CounterRng rng(seed, 0x4d454d42u);  // "MEMB"
    const double amp = kIrregularJitter * disc.ring_spacing_mm;
    for (uint32_t v = 1; v < disc.mesh.vertices.size(); ++v) {
      if (disc.rim[v]) continue;
      const double rho = amp * std::sqrt(rng.uniform_double(0, v, 0));
      const double phi = 2.0 * std::numbers::pi * rng.uniform_double(0, v, 1);
      disc.mesh.vertices[v].x() += rho * std::cos(phi);
      disc.mesh.vertices[v].y() += rho * std::sin(phi);
    }
    if (min_signed_area(disc.mesh) <= 0.0)
      throw std::logic_error("make_flat_disc: jitter inverted a triangle");
  }
  return disc;
}

double mean_edge_length(const SurfaceMesh& mesh) {
  std::set<std::pair<uint32_t, uint32_t>> edges;
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) edges.insert(std::minmax(t[k], t[(k + 1) % 3]));
  double sum = 0.0;
  for (const auto& [a, b] : edges) sum += (mesh.vertices[b] - mesh.vertices[a]).norm();
  return edges.empty() ? 0.0 : sum / static_cast<double>(edges.size());
}

double min_signed_area(const SurfaceMesh& mesh) {
  double m = std::numeric_limits<double>::infinity();
  for (const auto& t : mesh.triangles) m = std::min(m, signed_area(mesh, t));
  return m;
}

DiscBody make_disc_body(const FlatDisc& disc, double areal_density) {
  DiscBody body;
  const auto n = static_cast<uint32_t>(disc.mesh.vertices.size());
  table_append(body.particles, n);
  std::vector<double> mass(n, 0.0);
  const auto tcount = static_cast<uint32_t>(disc.mesh.triangles.size());
  table_append(body.triangles, tcount);
  for (uint32_t t = 0; t < tcount; ++t) {
    const auto& tri = disc.mesh.triangles[t];
    body.triangles.a[t] = tri[0], body.triangles.b[t] = tri[1], body.triangles.c[t] = tri[2];
    const double m3 = areal_density * std::fabs(signed_area(disc.mesh, tri)) / 3.0;
    for (uint32_t v : tri) mass[v] += m3;
  }
  Particles& p = body.particles;
  for (uint32_t v = 0; v < n; ++v) {
    p.x[v] = static_cast<float>(disc.mesh.vertices[v].x());
    p.y[v] = static_cast<float>(disc.mesh.vertices[v].y());
    p.z[v] = static_cast<float>(disc.mesh.vertices[v].z());
    p.kind[v] = disc.rim[v] ? ParticleKind::Anchored : ParticleKind::Free;
    p.inv_mass[v] = disc.rim[v] || mass[v] <= 0.0 ? 0.0f : static_cast<float>(1.0 / mass[v]);
  }
  return body;
}

}  // namespace phaco::reference
