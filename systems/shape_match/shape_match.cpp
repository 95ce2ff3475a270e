#include "systems/shape_match/shape_match.hpp"

#include <cassert>
#include <cmath>
#include <limits>

#include "engine/core/invariants.hpp"
#include "engine/schedule/parallel.hpp"

namespace phaco::shape_match {
namespace {

constexpr uint32_t kCellGrain = 4096;  // cells per chunk inside one large fragment

Quat to_quat(const Vec4T<double>& wxyz) {
  return Quat(wxyz(0), wxyz(1), wxyz(2), wxyz(3));
}

Vec4T<double> to_vec(const Quat& q) {
  return Vec4T<double>(q.w(), q.x(), q.y(), q.z());
}

// Same rotation, on the previous quaternion's side of the sphere (q and −q are one rotation).
Quat same_hemisphere(Quat q, const Quat& previous) {
  if (q.dot(previous) < 0) q.coeffs() = -q.coeffs();
  return q;
}

Moments<float> to_float(const Moments<double>& m) {
  Moments<float> f;
  f.count = m.count;
  f.mass = static_cast<float>(m.mass);
  f.rest_centroid = m.rest_centroid.cast<float>();
  f.current_centroid = m.current_centroid.cast<float>();
  f.cross = m.cross.cast<float>();
  f.rest_spread = static_cast<float>(m.rest_spread);
  f.current_spread = static_cast<float>(m.current_spread);
  return f;
}

void count_path(LensPassStats& s, MatchPath p) {
  switch (p) {
    case MatchPath::KeepPrevious:
      ++s.kept;
      break;
    case MatchPath::Fast:
      ++s.fast;
      break;
    case MatchPath::Exact:
      ++s.exact;
      break;
    case MatchPath::Continuous:
      ++s.continuous;
      break;
  }
}

LensPassStats merge_stats(LensPassStats a, const LensPassStats& b) {
  a.fragments += b.fragments;
  a.cells += b.cells;
  a.kept += b.kept;
  a.fast += b.fast;
  a.exact += b.exact;
  a.continuous += b.continuous;
  return a;
}

// Moments of a large fragment, reduced over fixed cell chunks in chunk order.
template <class P>
Moments<double> parallel_moments(std::span<const Vec3T<P>> rest, std::span<const Vec3T<P>> current,
                                 std::span<const P> masses, std::span<const uint32_t> ids) {
  const Vec3 rs = rest[ids[0]].template cast<double>();
  const Vec3 cs = current[ids[0]].template cast<double>();
  const MomentSums<double> sums = parallel_reduce_ordered(
      0u, static_cast<uint32_t>(ids.size()), kCellGrain, MomentSums<double>{},
      [&](uint32_t b, uint32_t e) {
        return accumulate_moments<double, P>(rest, current, masses, ids, b, e, rs, cs);
      },
      [](MomentSums<double> x, const MomentSums<double>& y) {
        return merge_sums(std::move(x), y);
      });
  return finish_moments(sums, rs, cs);
}

}  // namespace

FragmentMatch match_moments(const Moments<double>& m, const Quat& previous,
                            const MatchSettings& settings) {
  FragmentMatch out;
  out.rest_centroid = m.rest_centroid;
  out.current_centroid = m.current_centroid;
  out.rotation = previous;
  const double scale = 0.5 * (m.rest_spread + m.current_spread);
  if (m.count <= 1 || !(scale > 0)) return out;  // nothing but the translation is determined

  // One or two cells are collinear by construction: straight to the exact solve.
  if (m.count >= 3) {
    const bool use_float =
        settings.first_precision == Precision::Float && m.count > settings.small_fragment;
    Quat q;
    double gap;
    bool accept;
    if (use_float) {
      const HornResult<float> f = horn_solve(to_float(m), settings.first_solver);
      q = f.rotation.cast<double>().normalized();
      gap = f.gap;
      accept = !f.ill_conditioned;
    } else {
      const HornResult<double> f = horn_solve(m, settings.first_solver);
      q = f.rotation;
      gap = f.gap;
      accept = !f.ill_conditioned;
    }
    if (accept) {
      out.rotation = same_hemisphere(q, previous);
      out.gap = gap;
      out.path = MatchPath::Fast;
      return out;
    }
  }
  const HornResult<double> d = horn_solve(m, Solver::Eigen);
  out.gap = d.gap;
  if (!(d.top_eigenvalue > 64 * std::numeric_limits<double>::epsilon() * scale)) return out;
  if (d.gap >= settings.degenerate_gap) {
    out.rotation = same_hemisphere(d.rotation, previous);
    out.path = MatchPath::Exact;
    return out;
  }
  // Two-dimensional optimal set: the previous rotation's projection onto span{e1, e2}.
  const Vec4T<double> e1(d.rotation.w(), d.rotation.x(), d.rotation.y(), d.rotation.z());
  const Vec4T<double> p = to_vec(previous);
  Vec4T<double> q = e1.dot(p) * e1 + d.second.dot(p) * d.second;
  const double n = q.norm();
  q = n > 1e-12 ? Vec4T<double>(q / n) : e1;
  out.rotation = same_hemisphere(to_quat(q), previous);
  out.path = MatchPath::Continuous;
  return out;
}

template <class P>
FragmentMatch match_fragment(std::span<const Vec3T<P>> rest, std::span<const Vec3T<P>> current,
                             std::span<const P> masses, const Quat& previous,
                             const MatchSettings& settings, std::span<const uint32_t> ids) {
  return match_moments(fragment_moments<double, P>(rest, current, masses, ids), previous, settings);
}

template <class P>
void pull_to_goals(const FragmentMatch& f, std::span<const Vec3T<P>> rest,
                   std::span<Vec3T<P>> current, double stiffness, std::span<const uint32_t> ids) {
  assert(same_size(rest, current) && all_below(ids, rest.size()));
  const Mat3T<double> r = f.rotation.toRotationMatrix();
  const auto n = static_cast<uint32_t>(ids.empty() ? rest.size() : ids.size());
  for (uint32_t k = 0; k < n; ++k) {
    const uint32_t i = ids.empty() ? k : ids[k];
    const Vec3 g = r * (rest[i].template cast<double>() - f.rest_centroid) + f.current_centroid;
    const Vec3 x = current[i].template cast<double>();
    current[i] = (x + stiffness * (g - x)).template cast<P>();
  }
}

template <class P>
LensPassStats match_lens(std::span<const Vec3T<P>> rest, std::span<Vec3T<P>> current,
                         std::span<const P> masses, FragmentList fragments,
                         std::span<Quat> rotations, const MatchSettings& settings) {
  const uint32_t count = fragments.count();
  if (count == 0) return {};
  // One rotation per fragment, cells of the fragments within the list and the positions.
  assert(same_size(rest, current) && (masses.empty() || same_size(rest, masses)));
  assert(rotations.size() >= count && fragments.offsets[count] <= fragments.cells.size());
  // About kCellGrain cells per chunk of fragments; the grain depends only on the fragment list.
  const uint32_t cells = fragments.offsets[count];
  const uint32_t grain = std::max<uint32_t>(
      1, static_cast<uint32_t>(uint64_t{count} * kCellGrain / std::max(cells, 1u)));
  std::span<const Vec3T<P>> cur_view(current.data(), current.size());
  auto cells_of = [&](uint32_t f) {
    return fragments.cells.subspan(fragments.offsets[f],
                                   fragments.offsets[f + 1] - fragments.offsets[f]);
  };

  LensPassStats stats = parallel_reduce_ordered(
      0u, count, grain, LensPassStats{},
      [&](uint32_t b, uint32_t e) {
        LensPassStats s;
        for (uint32_t f = b; f < e; ++f) {
          const std::span<const uint32_t> ids = cells_of(f);
          if (ids.size() > kParallelCells) continue;  // below, with parallel moments
          const FragmentMatch fm =
              match_fragment<P>(rest, cur_view, masses, rotations[f], settings, ids);
          pull_to_goals<P>(fm, rest, current, settings.stiffness, ids);
          rotations[f] = fm.rotation;
          ++s.fragments;
          s.cells += static_cast<uint32_t>(ids.size());
          count_path(s, fm.path);
        }
        return s;
      },
      merge_stats);

  for (uint32_t f = 0; f < count; ++f) {
    const std::span<const uint32_t> ids = cells_of(f);
    if (ids.size() <= kParallelCells) continue;
    const FragmentMatch fm =
        match_moments(parallel_moments<P>(rest, cur_view, masses, ids), rotations[f], settings);
    parallel_for(0u, static_cast<uint32_t>(ids.size()), kCellGrain,
                 [&](uint32_t b, uint32_t e, int) {
                   pull_to_goals<P>(fm, rest, current, settings.stiffness, ids.subspan(b, e - b));
                 });
    rotations[f] = fm.rotation;
    ++stats.fragments;
    stats.cells += static_cast<uint32_t>(ids.size());
    count_path(stats, fm.path);
  }
  return stats;
}

#define PHACO_SHAPE_MATCH_INSTANTIATE(P)                                                          \
  template FragmentMatch match_fragment<P>(std::span<const Vec3T<P>>, std::span<const Vec3T<P>>,  \
                                           std::span<const P>, const Quat&, const MatchSettings&, \
                                           std::span<const uint32_t>);                            \
  template void pull_to_goals<P>(const FragmentMatch&, std::span<const Vec3T<P>>,                 \
                                 std::span<Vec3T<P>>, double, std::span<const uint32_t>);         \
  template LensPassStats match_lens<P>(std::span<const Vec3T<P>>, std::span<Vec3T<P>>,            \
                                       std::span<const P>, FragmentList, std::span<Quat>,         \
                                       const MatchSettings&);

PHACO_SHAPE_MATCH_INSTANTIATE(float)
PHACO_SHAPE_MATCH_INSTANTIATE(double)
#undef PHACO_SHAPE_MATCH_INSTANTIATE

}  // namespace phaco::shape_match
