#include "systems/springs/springs.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "engine/core/math.hpp"
#include "engine/schedule/parallel.hpp"

namespace phaco::springs {

namespace {

struct EdgeRecord {
  uint32_t i, j;
  double area;  // sum of the areas of the triangles sharing the edge, mm²
  double cot;   // half the sum of the cotangents of the angles opposite the edge
};

Vec3 position(const Particles& p, uint32_t v) {
  return {p.x[v], p.y[v], p.z[v]};
}

double triangle_area(const Particles& p, uint32_t a, uint32_t b, uint32_t c) {
  const Vec3 pa(p.x[a], p.y[a], p.z[a]), pb(p.x[b], p.y[b], p.z[b]), pc(p.x[c], p.y[c], p.z[c]);
  return 0.5 * (pb - pa).cross(pc - pa).norm();
}

}  // namespace

SpringConstants edge_spring_constants(const SpringMaterial& m, double l, double area_sum,
                                      double half_cot_sum) {
  static const double equilateral = std::sqrt(3.0) / 2.0;
  SpringConstants out;
  double k =
      m.sheet_modulus_mn_mm *
      (m.weighting == StiffnessWeighting::AreaWeighted && l > 0 ? area_sum / (l * l) : equilateral);
  if (m.law == SpringLaw::Quadratic) k /= m.quadratic_reference_mm;
  double rest = (1.0 - m.prestretch) * l;
  if (m.pretension == Pretension::Cotangent && k > 0) {
    const double tension = 1.5 * m.prestretch * m.sheet_modulus_mn_mm * half_cot_sum * l;  // mN
    const double extension = m.law == SpringLaw::Linear
                                 ? tension / k
                                 : std::copysign(std::sqrt(std::fabs(tension) / k), tension);
    if (l - extension < 0.5 * l) {
      out.pretension_clamped = true;  // fall back to the uniform pre-stretch for this edge
    } else {
      rest = l - extension;
    }
  }
  out.stiffness = k;
  out.rest_length = rest;
  return out;
}

Springs build_springs(const Particles& particles, const Triangles& triangles,
                      const SpringMaterial& m, uint32_t* clamped_pretension) {
  if (!(m.prestretch >= 0.0 && m.prestretch < 1.0))
    throw std::invalid_argument("prestretch must be in [0, 1)");
  std::vector<EdgeRecord> edges;
  edges.reserve(triangles.slots.size() * 3);
  for (uint32_t t = 0; t < triangles.slots.size(); ++t) {
    if (!triangles.slots.alive(t)) continue;
    const uint32_t v[3] = {triangles.a[t], triangles.b[t], triangles.c[t]};
    const double area = triangle_area(particles, v[0], v[1], v[2]);
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = v[k], b = v[(k + 1) % 3], o = v[(k + 2) % 3];
      const Vec3 u = position(particles, a) - position(particles, o),
                 w = position(particles, b) - position(particles, o);
      const double cross = u.cross(w).norm();
      const double half_cot = cross > 0 ? 0.5 * u.dot(w) / cross : 0.0;
      edges.push_back({std::min(a, b), std::max(a, b), area, half_cot});
    }
  }
  std::sort(edges.begin(), edges.end(), [](const EdgeRecord& x, const EdgeRecord& y) {
    return x.i != y.i ? x.i < y.i : x.j < y.j;
  });

  Springs s;
  for (size_t e = 0; e < edges.size();) {
    double area = 0.0, cot = 0.0;
    size_t f = e;
    for (; f < edges.size() && edges[f].i == edges[e].i && edges[f].j == edges[e].j; ++f) {
      area += edges[f].area;
      cot += edges[f].cot;
    }
    const uint32_t a = edges[e].i, b = edges[e].j;
    const double dx = particles.x[b] - particles.x[a], dy = particles.y[b] - particles.y[a],
                 dz = particles.z[b] - particles.z[a];
    const double l = std::sqrt(dx * dx + dy * dy + dz * dz);
    const SpringConstants sc = edge_spring_constants(m, l, area, cot);
    // As the cut's re-springing does: such an edge keeps the uniform pre-stretch, and is counted.
    if (sc.pretension_clamped && clamped_pretension != nullptr) ++*clamped_pretension;
    const double k = sc.stiffness, rest = sc.rest_length;
    const uint32_t idx = table_add(s);
    s.i[idx] = a;
    s.j[idx] = b;
    s.rest_length[idx] = static_cast<float>(rest);
    s.stiffness[idx] = static_cast<float>(k);
    e = f;
  }
  return s;
}

SpringGraph build_spring_graph(const Springs& springs, uint32_t particle_count) {
  SpringGraph g;
  g.row_size.assign(particle_count, 0);
  const uint32_t ns = springs.slots.size();
  for (uint32_t e = 0; e < ns; ++e) {
    if (!springs.slots.alive(e)) continue;
    if (springs.i[e] >= particle_count || springs.j[e] >= particle_count)
      throw std::invalid_argument("build_spring_graph: spring " + std::to_string(e) +
                                  " names a particle beyond " + std::to_string(particle_count));
    ++g.row_size[springs.i[e]];
    ++g.row_size[springs.j[e]];
  }
  // Room for the particles and row moves that cuts add, so a cut frame does not reallocate (and
  // copy) per-particle arrays the size of the mesh; beyond that they grow geometrically.
  const size_t room = size_t{particle_count} + particle_count / 4 + 64;
  g.row_begin.reserve(room), g.row_size.reserve(room), g.row_capacity.reserve(room);
  g.row_begin.resize(particle_count);
  g.row_capacity.resize(particle_count);
  uint32_t at = 0;
  for (uint32_t p = 0; p < particle_count; ++p) {
    g.row_begin[p] = at;
    g.row_capacity[p] = g.row_size[p] + kGraphRowSlack;
    at += g.row_capacity[p];
  }
  // Room for rows that move when they outgrow their slack, so the first cuts do not reallocate.
  g.neighbour.reserve(at + at / 4 + 512), g.spring.reserve(at + at / 4 + 512);
  g.neighbour.assign(at, kInvalidIndex);
  g.spring.assign(at, kInvalidIndex);
  std::vector<uint32_t> fill(g.row_begin);
  for (uint32_t e = 0; e < ns; ++e) {
    if (!springs.slots.alive(e)) continue;
    const uint32_t a = springs.i[e], b = springs.j[e];
    g.neighbour[fill[a]] = b, g.spring[fill[a]++] = e;
    g.neighbour[fill[b]] = a, g.spring[fill[b]++] = e;
  }
  // Sort each row by neighbour so the graph does not depend on the spring table's order.
  std::vector<std::pair<uint32_t, uint32_t>> row;
  for (uint32_t p = 0; p < particle_count; ++p) {
    row.clear();
    for (uint32_t k = g.begin(p); k < g.end(p); ++k) row.emplace_back(g.neighbour[k], g.spring[k]);
    std::sort(row.begin(), row.end());
    for (uint32_t k = g.begin(p); k < g.end(p); ++k) {
      g.neighbour[k] = row[k - g.begin(p)].first;
      g.spring[k] = row[k - g.begin(p)].second;
    }
  }
  return g;
}

namespace {

// Puts (q, e) into p's row at its sorted place; a full row first moves to the end of the arrays
// with twice the room (amortised: the arrays grow geometrically).
void row_insert(SpringGraph& g, uint32_t p, uint32_t q, uint32_t e) {
  for (uint32_t k = g.begin(p); k < g.end(p); ++k)
    if (g.spring[k] == e) return;  // already there
  if (g.row_size[p] == g.row_capacity[p]) {
    const uint32_t from = g.row_begin[p], size = g.row_size[p];
    const uint32_t capacity = std::max<uint32_t>(2 * size, 4);
    const uint32_t to = static_cast<uint32_t>(g.neighbour.size());
    g.neighbour.resize(to + capacity, kInvalidIndex);
    g.spring.resize(to + capacity, kInvalidIndex);
    std::copy_n(g.neighbour.begin() + from, size, g.neighbour.begin() + to);
    std::copy_n(g.spring.begin() + from, size, g.spring.begin() + to);
    g.row_begin[p] = to;
    g.row_capacity[p] = capacity;
  }
  uint32_t k = g.end(p);
  for (; k > g.begin(p) &&
         (g.neighbour[k - 1] > q || (g.neighbour[k - 1] == q && g.spring[k - 1] > e));
       --k) {
    g.neighbour[k] = g.neighbour[k - 1];
    g.spring[k] = g.spring[k - 1];
  }
  g.neighbour[k] = q, g.spring[k] = e;
  ++g.row_size[p];
}

void row_erase(SpringGraph& g, uint32_t p, uint32_t e) {
  if (p >= g.particle_count()) return;
  const uint32_t end = g.end(p);
  for (uint32_t k = g.begin(p); k < end; ++k) {
    if (g.spring[k] != e) continue;
    std::copy(g.neighbour.begin() + k + 1, g.neighbour.begin() + end, g.neighbour.begin() + k);
    std::copy(g.spring.begin() + k + 1, g.spring.begin() + end, g.spring.begin() + k);
    --g.row_size[p];
    return;
  }
}

}  // namespace

void patch_spring_graph(SpringGraph& g, const Springs& springs, uint32_t particle_count,
                        std::span<const uint32_t> removed, std::span<const uint32_t> added) {
  // New rows start empty with a little room at the end of the arrays (a cut point gets about six
  // springs); per-particle arrays grow geometrically.
  constexpr uint32_t kNewRowCapacity = 8;
  for (uint32_t p = g.particle_count(); p < particle_count; ++p) {
    g.row_begin.push_back(static_cast<uint32_t>(g.neighbour.size()));
    g.row_size.push_back(0);
    g.row_capacity.push_back(kNewRowCapacity);
    g.neighbour.resize(g.neighbour.size() + kNewRowCapacity, kInvalidIndex);
    g.spring.resize(g.spring.size() + kNewRowCapacity, kInvalidIndex);
  }
  for (uint32_t e : removed) {
    if (e >= springs.slots.size()) continue;
    row_erase(g, springs.i[e], e);
    row_erase(g, springs.j[e], e);
  }
  for (uint32_t e : added) {
    if (!springs.slots.alive(e)) continue;  // added and removed again since the last patch
    const uint32_t a = springs.i[e], b = springs.j[e];
    if (a >= particle_count || b >= particle_count)
      throw std::invalid_argument("patch_spring_graph: spring " + std::to_string(e) +
                                  " names a particle beyond " + std::to_string(particle_count));
    row_insert(g, a, b, e);
    row_insert(g, b, a, e);
  }
}

std::vector<std::pair<uint32_t, uint32_t>> graph_row(const SpringGraph& g, uint32_t p) {
  std::vector<std::pair<uint32_t, uint32_t>> row;
  for (uint32_t k = g.begin(p); k < g.end(p); ++k) row.emplace_back(g.neighbour[k], g.spring[k]);
  return row;
}

SpringBlocks plan_blocks(const Springs& s, uint32_t particle_count, uint32_t target_blocks) {
  uint32_t max_span = 0;
  for (uint32_t e = 0; e < s.slots.size(); ++e) {
    if (s.j[e] < s.i[e]) throw std::invalid_argument("plan_blocks: springs must have i < j");
    if (e > 0 && s.i[e] < s.i[e - 1])
      throw std::invalid_argument("plan_blocks: springs must be sorted by i");
    max_span = std::max(max_span, s.j[e] - s.i[e]);
  }
  const uint32_t n = std::max<uint32_t>(particle_count, 1);
  const uint32_t by_target =
      (n + std::max<uint32_t>(target_blocks, 1) - 1) / std::max<uint32_t>(target_blocks, 1);
  const uint32_t block_size = std::max(by_target, max_span + 1);
  SpringBlocks b;
  for (uint32_t start = 0; start < n; start += block_size) b.particle_begin.push_back(start);
  b.particle_begin.push_back(n);
  for (uint32_t k = 0; k < b.particle_begin.size(); ++k) {
    const auto it = std::lower_bound(s.i.begin(), s.i.end(), b.particle_begin[k]);
    b.spring_begin.push_back(k + 1 == b.particle_begin.size()
                                 ? s.slots.size()
                                 : static_cast<uint32_t>(it - s.i.begin()));
  }
  return b;
}

namespace {

// Springs go through in chunks of kChunk: gather the end positions into contiguous arrays
// (scalar loads), compute F/l for the whole chunk in a loop with no indirection — which the
// compiler turns into 4-wide SSE2 sqrt and divide, the two operations that bound a scalar spring
// at ~3.7 ns — then scatter. The order in which forces reach a particle is the spring order, as
// in a plain loop, so the result is deterministic.
constexpr uint32_t kChunk = 64;

template <SpringLaw kLaw>
void spring_range(const Springs& s, uint32_t begin, uint32_t end, const Particles& p, Forces& f) {
  alignas(16) float dx[kChunk], dy[kChunk], dz[kChunk], scale[kChunk];
  const uint32_t* si = s.i.data();
  const uint32_t* sj = s.j.data();
  const float* rest = s.rest_length.data();
  const float* k = s.stiffness.data();
  const float *x = p.x.data(), *y = p.y.data(), *z = p.z.data();
  float *fx = f.fx.data(), *fy = f.fy.data(), *fz = f.fz.data();
  for (uint32_t base = begin; base < end; base += kChunk) {
    const uint32_t n = std::min(kChunk, end - base);
    for (uint32_t t = 0; t < n; ++t) {
      const uint32_t i = si[base + t], j = sj[base + t];
      dx[t] = x[j] - x[i];
      dy[t] = y[j] - y[i];
      dz[t] = z[j] - z[i];
    }
    const float* r = rest + base;
    const float* kk = k + base;
    for (uint32_t t = 0; t < n; ++t) {
      const float l = std::sqrt(dx[t] * dx[t] + dy[t] * dy[t] + dz[t] * dz[t]);
      const float ext = l - r[t];
      float mag = kk[t] * ext;
      if constexpr (kLaw == SpringLaw::Quadratic) mag *= std::fabs(ext);
      // Coincident ends (l = 0) have d = 0: a finite scale times d gives no force, no branch.
      scale[t] = mag / std::max(l, 1e-30f);
    }
    // Consecutive springs share i (sorted): i's force stays in registers until i changes, so
    // the scatter does not chain a store-to-load dependency through f[i] on every spring.
    uint32_t t = 0;
    while (t < n) {
      const uint32_t i = si[base + t];
      float ax = 0.0f, ay = 0.0f, az = 0.0f;
      for (; t < n && si[base + t] == i; ++t) {
        const uint32_t j = sj[base + t];
        const float gx = scale[t] * dx[t], gy = scale[t] * dy[t], gz = scale[t] * dz[t];
        ax += gx, ay += gy, az += gz;
        fx[j] -= gx, fy[j] -= gy, fz[j] -= gz;
      }
      fx[i] += ax, fy[i] += ay, fz[i] += az;
    }
  }
}

void spring_range(const Springs& s, uint32_t begin, uint32_t end, SpringLaw law, const Particles& p,
                  Forces& f) {
  if (law == SpringLaw::Linear) {
    spring_range<SpringLaw::Linear>(s, begin, end, p, f);
  } else {
    spring_range<SpringLaw::Quadratic>(s, begin, end, p, f);
  }
}

}  // namespace

void add_spring_forces(const Springs& s, const SpringBlocks& blocks, SpringLaw law,
                       const Particles& p, Forces& f) {
  const uint32_t nb = blocks.count();
  if (nb <= 2) {
    spring_range(s, 0, s.slots.size(), law, p, f);
    return;
  }
  for (uint32_t parity = 0; parity < 2; ++parity) {
    const uint32_t count = (nb - parity + 1) / 2;
    parallel_for(0, count, 1, [&](uint32_t begin, uint32_t end, int) {
      for (uint32_t k = begin; k < end; ++k) {
        const uint32_t b = 2 * k + parity;
        spring_range(s, blocks.spring_begin[b], blocks.spring_begin[b + 1], law, p, f);
      }
    });
  }
  spring_range(s, blocks.tail_begin(), s.slots.size(), law, p,
               f);  // what cuts added since the plan
}

double spring_energy(const Springs& s, SpringLaw law, const Particles& p) {
  double energy = 0.0;
  for (uint32_t e = 0; e < s.slots.size(); ++e) {
    if (!s.slots.alive(e)) continue;
    const uint32_t i = s.i[e], j = s.j[e];
    const double dx = p.x[j] - p.x[i], dy = p.y[j] - p.y[i], dz = p.z[j] - p.z[i];
    const double ext = std::sqrt(dx * dx + dy * dy + dz * dz) - s.rest_length[e];
    energy += law == SpringLaw::Linear ? 0.5 * s.stiffness[e] * ext * ext
                                       : s.stiffness[e] * std::fabs(ext) * ext * ext / 3.0;
  }
  return energy;
}

double max_stiffness_over_mass(const Springs& s, const Particles& p) {
  std::vector<double> k_sum(p.slots.size(), 0.0);
  for (uint32_t e = 0; e < s.slots.size(); ++e) {
    if (!s.slots.alive(e)) continue;
    k_sum[s.i[e]] += s.stiffness[e];
    k_sum[s.j[e]] += s.stiffness[e];
  }
  double worst = 0.0;
  for (uint32_t v = 0; v < p.slots.size(); ++v) worst = std::max(worst, k_sum[v] * p.inv_mass[v]);
  return worst;
}

}  // namespace phaco::springs
