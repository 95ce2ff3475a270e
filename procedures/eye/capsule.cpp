// Anterior capsule meshes on the anterior lens surface.
//
// Curvilinear layout (seed 003 §III.D: "each vertex has 4 or 8 neighbours except the centre";
// seed 004: "a curvilinear mesh of nodes and springs"). Rings are equally spaced in meridian arc
// length Δs, spokes are radial. Between two rings with the same spoke count n (even) each quad
// gets the diagonal of a checkerboard, so ring k vertex j has 8 neighbours when k+j is even and
// 4 when it is odd:
//
//     ring k+1   o---o---o---o         o(k+1,j) ... spokes run up the page, rings across
//                | \ | / | \ |
//     ring k     o---o---o---o         diagonal from (k,j) to (k+1,j+1) when k+j is even,
//                | / | \ | / |         else from (k+1,j) to (k,j+1)
//     ring k-1   o---o---o---o
//
// Spokes double at a transition ring, where the arc between spokes 2πr/n would exceed 2Δs. A
// transition strip from n inner to 2n outer vertices is, for each inner pair (i_j, i_j+1) and outer
// (o_2j, o_2j+1, o_2j+2): (i_j, o_2j, o_2j+1), (i_j, o_2j+1, i_j+1), (i_j+1, o_2j+1, o_2j+2); the
// new spoke's vertex o_2j+1 thus links down to both inner neighbours. Vertices on the two rings of
// a transition strip, and on ring 1 (joined to the centre by a fan of n_1 = 8), are the exceptions
// to the 4-or-8 rule; their share shrinks as the level rises.
//
// Isotropic layout: the same arc-length rings with n ∝ r (near-equilateral triangles), odd rings
// turned by half a step and strips zipped by angle (revolve.hpp): interior valence about 6.
//
// The ring count K is the one whose vertex count is closest to the resolution's target.
#include <cmath>
#include <cstdlib>
#include <numbers>
#include <vector>

#include "procedures/eye/eye_geometry.hpp"
#include "procedures/eye/eye_mesh.hpp"
#include "procedures/eye/revolve.hpp"

namespace phaco::eye {
namespace {

constexpr uint32_t kFirstRingSpokes = 8;
constexpr double kSpokeDoublingRatio = 2.0;  // spoke arc / ring spacing that triggers a doubling
constexpr int kMaxRings = 4096;

MeridianCurve capsule_meridian(const EyeGeometry& g) {
  const double a = g.lens_a, c = g.lens_c_anterior;
  // Ellipse angle t: r = a sin t, z = c cos t, from the pole to the capsule rim.
  return MeridianCurve(
      [=](double t) {
        return RZ{a * std::sin(t), c * std::cos(t)};
      },
      0.0, std::asin(g.capsule_radius / a));
}

std::vector<RZ> rings_for(const MeridianCurve& curve, int ring_count) {
  return profile_rings({curve}, curve.length() / ring_count);
}

// Spoke counts of rings 1..K (index 0 is the centre, count 1).
std::vector<uint32_t> curvilinear_counts(const std::vector<RZ>& rings, double spacing) {
  std::vector<uint32_t> counts(rings.size(), 1);
  for (size_t k = 1; k < rings.size(); ++k) {
    if (k == 1) {
      counts[k] = kFirstRingSpokes;
      continue;
    }
    counts[k] = counts[k - 1];
    if (2.0 * std::numbers::pi * rings[k].r / counts[k] > kSpokeDoublingRatio * spacing)
      counts[k] *= 2;
  }
  return counts;
}

std::vector<uint32_t> isotropic_counts(const std::vector<RZ>& rings, double spacing) {
  std::vector<uint32_t> counts;
  counts.reserve(rings.size());
  for (const RZ& rz : rings) counts.push_back(ring_vertex_count(rz.r, spacing, 3));
  return counts;
}

uint64_t sum(const std::vector<uint32_t>& v) {
  uint64_t s = 0;
  for (uint32_t x : v) s += x;
  return s;
}

// Ring count whose vertex total is closest to the target (ties to fewer rings).
int choose_ring_count(const MeridianCurve& curve, CapsuleLayout layout, uint32_t target) {
  int best = 1;
  int64_t best_err = -1;
  for (int k = 1; k <= kMaxRings; ++k) {
    const auto rings = rings_for(curve, k);
    const double spacing = curve.length() / k;
    const auto counts = layout == CapsuleLayout::Curvilinear ? curvilinear_counts(rings, spacing)
                                                             : isotropic_counts(rings, spacing);
    const auto total = static_cast<int64_t>(sum(counts));
    const int64_t err = std::llabs(total - static_cast<int64_t>(target));
    if (best_err < 0 || err < best_err) {
      best = k;
      best_err = err;
    }
    if (total > static_cast<int64_t>(target)) break;  // counts grow with k
  }
  return best;
}

SurfaceMesh build_curvilinear(const std::vector<RZ>& rings, double spacing) {
  const auto counts = curvilinear_counts(rings, spacing);
  SurfaceMesh mesh;
  std::vector<Ring> made(rings.size());
  for (size_t k = 0; k < rings.size(); ++k) {
    made[k] = Ring{rings[k], counts[k], 0.0};
    add_ring(mesh, made[k]);
  }
  for (size_t k = 1; k < rings.size(); ++k) {
    const Ring& in = made[k - 1];
    const Ring& out = made[k];
    const auto iv = [&](uint32_t j) { return in.first + j % in.count; };
    const auto ov = [&](uint32_t j) { return out.first + j % out.count; };
    if (in.count == 1) {
      join_rings(mesh, in, out);  // centre fan
    } else if (out.count == in.count) {
      for (uint32_t j = 0; j < in.count; ++j) {
        if ((k - 1 + j) % 2 == 0) {  // diagonal (k-1, j) - (k, j+1)
          mesh.triangles.push_back({iv(j), ov(j), ov(j + 1)});
          mesh.triangles.push_back({iv(j), ov(j + 1), iv(j + 1)});
        } else {  // diagonal (k, j) - (k-1, j+1)
          mesh.triangles.push_back({iv(j), ov(j), iv(j + 1)});
          mesh.triangles.push_back({iv(j + 1), ov(j), ov(j + 1)});
        }
      }
    } else {  // transition: out.count == 2 * in.count
      for (uint32_t j = 0; j < in.count; ++j) {
        mesh.triangles.push_back({iv(j), ov(2 * j), ov(2 * j + 1)});
        mesh.triangles.push_back({iv(j), ov(2 * j + 1), iv(j + 1)});
        mesh.triangles.push_back({iv(j + 1), ov(2 * j + 1), ov(2 * j + 2)});
      }
    }
  }
  return mesh;
}

}  // namespace

const char* to_string(CapsuleLayout layout) {
  return layout == CapsuleLayout::Curvilinear ? "curvilinear" : "isotropic";
}

SurfaceMesh make_capsule(const EyeParams& params, const Resolution& res, CapsuleLayout layout) {
  const EyeGeometry g = eye_geometry(params);
  const MeridianCurve curve = capsule_meridian(g);
  const int ring_count = choose_ring_count(curve, layout, res.capsule_vertices);
  const auto rings = rings_for(curve, ring_count);
  const double spacing = curve.length() / ring_count;
  SurfaceMesh mesh = layout == CapsuleLayout::Curvilinear ? build_curvilinear(rings, spacing)
                                                          : revolve(rings, spacing);
  orient_toward_plus_z(mesh);
  return mesh;
}

}  // namespace phaco::eye
