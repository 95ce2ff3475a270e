#include "perf/lens/shape_match_measure.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <span>

#include "perf/lens/shape_match_fixture.hpp"
#include "perf/timing.hpp"
#include "systems/shape_match/shape_match.hpp"

namespace phaco::perf {
namespace {

using shape_match::HornResult;
using shape_match::Mat3T;
using shape_match::Solver;

constexpr double kDeg = 180.0 / M_PI;

std::vector<Vec3f> to_float(const std::vector<Vec3>& v) {
  std::vector<Vec3f> out(v.size());
  for (size_t i = 0; i < v.size(); ++i) out[i] = v[i].cast<float>();
  return out;
}

template <class T>
std::span<const T> cs(const std::vector<T>& v) {
  return {v.data(), v.size()};
}

// What a method returns for one fragment: a 3×3 matrix (rotation or reflection), the centroids,
// and whether it says the result is determined.
struct Fit {
  Mat3T<double> r;
  Vec3 rest_centroid, current_centroid;
  bool flagged = false;
};

using Method = std::function<Fit(const std::vector<Vec3>&, const std::vector<Vec3>&, const Quat&)>;

template <class T>
Fit horn_fit(const std::vector<Vec3>& a, const std::vector<Vec3>& b, Solver s) {
  HornResult<T> h;
  if constexpr (sizeof(T) == 4) {
    const auto af = to_float(a), bf = to_float(b);
    h = shape_match::horn<float, float>(cs(af), cs(bf), {}, s);
  } else {
    h = shape_match::horn<double, double>(cs(a), cs(b), {}, s);
  }
  return {h.rotation.template cast<double>().toRotationMatrix(),
          h.rest_centroid.template cast<double>(), h.current_centroid.template cast<double>(),
          h.ill_conditioned};
}

Fit polar_fit(const std::vector<Vec3>& a, const std::vector<Vec3>& b, bool det_check) {
  const auto m = shape_match::fragment_moments<double, double>(cs(a), cs(b), {});
  const auto p = shape_match::polar_solve(m, det_check);
  return {p.rotation, m.rest_centroid, m.current_centroid, false};
}

shape_match::MatchSettings float_first() {
  shape_match::MatchSettings s;
  s.first_precision = shape_match::Precision::Float;
  return s;
}

Fit policy_fit(const std::vector<Vec3>& a, const std::vector<Vec3>& b, const Quat& previous,
               const shape_match::MatchSettings& settings) {
  const auto f = shape_match::match_fragment<double>(cs(a), cs(b), {}, previous, settings);
  const bool determined =
      f.path == shape_match::MatchPath::Fast || f.path == shape_match::MatchPath::Exact;
  return Fit{f.rotation.toRotationMatrix(), f.rest_centroid, f.current_centroid, !determined};
}

std::vector<std::pair<std::string, Method>> methods() {
  return {
      {"horn_eigen_float",
       [](auto& a, auto& b, auto&) { return horn_fit<float>(a, b, Solver::Eigen); }},
      {"horn_eigen_double",
       [](auto& a, auto& b, auto&) { return horn_fit<double>(a, b, Solver::Eigen); }},
      {"horn_quartic_float",
       [](auto& a, auto& b, auto&) { return horn_fit<float>(a, b, Solver::Quartic); }},
      {"horn_quartic_double",
       [](auto& a, auto& b, auto&) { return horn_fit<double>(a, b, Solver::Quartic); }},
      {"polar_det", [](auto& a, auto& b, auto&) { return polar_fit(a, b, true); }},
      {"polar_no_det", [](auto& a, auto& b, auto&) { return polar_fit(a, b, false); }},
      {"policy",
       [](auto& a, auto& b, const Quat& previous) { return policy_fit(a, b, previous, {}); }},
      {"policy_float_first",
       [](auto& a, auto& b, const Quat& previous) {
         return policy_fit(a, b, previous, float_first());
       }},
  };
}

// Rotation angle of Rtrueᵀ R (for a reflection, of its closest rotation's trace formula, clamped).
double angle_deg(const Mat3T<double>& truth, const Mat3T<double>& r) {
  const double c = std::clamp(((truth.transpose() * r).trace() - 1) / 2, -1.0, 1.0);
  return std::acos(c) * kDeg;
}

}  // namespace

std::vector<ShapeDegenerateRow> measure_shape_degenerate(int trials, uint64_t seed) {
  struct Case {
    std::string name;
    std::function<std::vector<Vec3>(shape::Gen&)> rest;
    double noise = 0;
    bool mirror = false;
  };
  const std::vector<Case> cases = {
      {"one_cell", [](shape::Gen& g) { return shape::box_cloud(g, 1); }},
      {"two_cells", [](shape::Gen& g) { return shape::box_cloud(g, 2); }},
      {"three_collinear", [](shape::Gen& g) { return shape::line_cloud(g, 3, 0.0); }},
      {"nearly_collinear_1e-4", [](shape::Gen& g) { return shape::line_cloud(g, 8, 1e-4); }},
      {"coplanar", [](shape::Gen& g) { return shape::plane_cloud(g, 6); }},
      {"noisy", [](shape::Gen& g) { return shape::box_cloud(g, 20); }, 0.05},
      {"reflected", [](shape::Gen& g) { return shape::box_cloud(g, 10); }, 0.0, true},
  };
  std::vector<ShapeDegenerateRow> rows;
  for (const Case& c : cases) {
    for (const auto& [name, method] : methods()) {
      shape::Gen g(seed);  // the same clouds for every method
      ShapeDegenerateRow row{c.name, name, trials, 0, 0, 1e300, 0, 0};
      double sum = 0;
      for (int t = 0; t < trials; ++t) {
        const std::vector<Vec3> a = c.rest(g);
        const Quat truth = g.rotation();
        const Vec3 move = g.in_box(2);
        std::vector<Vec3> b(a.size());
        for (size_t i = 0; i < a.size(); ++i) {
          b[i] = truth * a[i] + move + c.noise * g.in_box(1);
          if (c.mirror) b[i].x() = -b[i].x();
        }
        // The policy's previous rotation: the truth one frame earlier (1° back about a random
        // axis).
        const Quat previous =
            Quat(Eigen::AngleAxisd(M_PI / 180, g.rotation() * Vec3::UnitZ())) * truth;
        const Fit f = method(a, b, previous);
        const double e = angle_deg(truth.toRotationMatrix(), f.r);
        row.max_angle_deg = std::max(row.max_angle_deg, e);
        sum += e;
        row.min_det = std::min(row.min_det, f.r.determinant());
        for (size_t i = 0; i < a.size(); ++i)
          row.max_goal_mm = std::max(
              row.max_goal_mm, (f.r * (a[i] - f.rest_centroid) + f.current_centroid - b[i]).norm());
        row.flagged += f.flagged ? 1 : 0;
      }
      row.mean_angle_deg = sum / trials;
      rows.push_back(row);
    }
  }
  return rows;
}

std::vector<ShapePrecisionRow> measure_shape_precision(int trials, uint64_t seed) {
  std::vector<ShapePrecisionRow> rows;
  const std::vector<std::string> names = {
      "horn_eigen_float", "horn_quartic_float", "horn_eigen_double", "horn_quartic_double",
      "policy",           "policy_float_first"};
  for (int cells : {4, 16}) {
    for (double offset : {1e-1, 1e-2, 1e-3, 1e-4, 1e-5}) {
      for (const std::string& name : names) {
        shape::Gen g(seed);
        ShapePrecisionRow row{offset, cells, name, trials, 0, 0};
        std::vector<double> gaps;
        for (int t = 0; t < trials; ++t) {
          const auto a = shape::line_cloud(g, cells, offset);
          const Quat truth = g.rotation();
          std::vector<Vec3> b(a.size());
          for (size_t i = 0; i < a.size(); ++i) b[i] = truth * a[i] + Vec3(0.3, 0.2, -0.1);
          Quat q;
          if (name == "horn_eigen_double") {
            const auto h = shape_match::horn<double, double>(cs(a), cs(b), {});
            q = h.rotation;
            gaps.push_back(h.gap);
          } else if (name == "horn_quartic_double") {
            q = shape_match::horn<double, double>(cs(a), cs(b), {}, Solver::Quartic).rotation;
          } else if (name == "policy") {
            q = shape_match::match_fragment<double>(cs(a), cs(b), {}, truth).rotation;
          } else if (name == "policy_float_first") {
            q = shape_match::match_fragment<double>(cs(a), cs(b), {}, truth, float_first())
                    .rotation;
          } else {
            const auto af = to_float(a), bf = to_float(b);
            q = shape_match::horn<float, float>(
                    cs(af), cs(bf), {},
                    name == "horn_eigen_float" ? Solver::Eigen : Solver::Quartic)
                    .rotation.cast<double>();
          }
          row.max_angle_deg =
              std::max(row.max_angle_deg, shape_match::rotation_angle(q, truth) * kDeg);
        }
        if (!gaps.empty()) {
          std::nth_element(gaps.begin(), gaps.begin() + gaps.size() / 2, gaps.end());
          row.median_gap = gaps[gaps.size() / 2];
        }
        rows.push_back(row);
      }
    }
  }
  return rows;
}

std::vector<ShapeTimingRow> measure_shape_timing(double min_seconds) {
  constexpr int kBatch =
      256;  // different fragments per timed call, so no branch is learnt by heart
  std::vector<ShapeTimingRow> rows;
  for (int cells : {1, 2, 3, 4, 8, 64}) {
    shape::Gen g(cells);
    std::vector<std::vector<Vec3>> rest(kBatch), cur(kBatch);
    std::vector<std::vector<Vec3f>> rest_f(kBatch), cur_f(kBatch);
    std::vector<shape_match::Moments<double>> md(kBatch);
    std::vector<shape_match::Moments<float>> mf(kBatch);
    for (int k = 0; k < kBatch; ++k) {
      rest[k] = shape::box_cloud(g, cells);
      const Quat r = g.rotation();
      cur[k].resize(cells);
      for (int i = 0; i < cells; ++i)
        cur[k][i] = r * rest[k][i] + Vec3(0.1, 0.2, 0.3) + 0.01 * g.in_box(1);
      rest_f[k] = to_float(rest[k]);
      cur_f[k] = to_float(cur[k]);
      md[k] = shape_match::fragment_moments<double, double>(cs(rest[k]), cs(cur[k]), {});
      mf[k] = shape_match::fragment_moments<float, float>(cs(rest_f[k]), cs(cur_f[k]), {});
    }
    volatile double sink = 0;
    auto time_batch = [&](auto&& one) {
      return seconds_per_call(1, min_seconds, 3,
                              [&] {
                                double s = 0;
                                for (int k = 0; k < kBatch; ++k) s += one(k);
                                sink = sink + s;
                              }) /
             kBatch * 1e9;
    };
    auto add = [&](const std::string& name, auto&& full, auto&& solve) {
      rows.push_back({name, cells, time_batch(full), time_batch(solve)});
    };
    for (Solver s : {Solver::Eigen, Solver::Quartic}) {
      const std::string tag = s == Solver::Eigen ? "eigen" : "quartic";
      add(
          "horn_" + tag + "_float",
          [&](int k) {
            return shape_match::horn<float, float>(cs(rest_f[k]), cs(cur_f[k]), {}, s).rotation.w();
          },
          [&](int k) { return shape_match::horn_solve(mf[k], s).rotation.w(); });
      add(
          "horn_" + tag + "_double",
          [&](int k) {
            return shape_match::horn<double, double>(cs(rest[k]), cs(cur[k]), {}, s).rotation.w();
          },
          [&](int k) { return shape_match::horn_solve(md[k], s).rotation.w(); });
    }
    add(
        "polar_float",
        [&](int k) {
          return shape_match::polar<float, float>(cs(rest_f[k]), cs(cur_f[k]), {}, true).det;
        },
        [&](int k) { return shape_match::polar_solve(mf[k], true).det; });
    add(
        "polar_double",
        [&](int k) {
          return shape_match::polar<double, double>(cs(rest[k]), cs(cur[k]), {}, true).det;
        },
        [&](int k) { return shape_match::polar_solve(md[k], true).det; });
    add(
        "policy",
        [&](int k) {
          return shape_match::match_fragment<double>(cs(rest[k]), cs(cur[k]), {}, Quat::Identity())
              .rotation.w();
        },
        [&](int k) { return shape_match::match_moments(md[k], Quat::Identity()).rotation.w(); });
    const shape_match::MatchSettings ff = float_first();
    add(
        "policy_float_first",
        [&](int k) {
          return shape_match::match_fragment<double>(cs(rest[k]), cs(cur[k]), {}, Quat::Identity(),
                                                     ff)
              .rotation.w();
        },
        [&](int k) {
          return shape_match::match_moments(md[k], Quat::Identity(), ff).rotation.w();
        });
  }
  return rows;
}

std::vector<ShapeLensRow> measure_shape_lens(int level, std::vector<uint32_t> fragment_counts,
                                             std::vector<int> threads, double min_seconds) {
  std::vector<ShapeLensRow> rows;
  for (uint32_t fragments : fragment_counts) {
    shape::LensFragments l = shape::make_lens_fragments(level, fragments);
    shape_match::MatchSettings settings;
    settings.stiffness = 0.5;
    const shape_match::FragmentList list{l.offsets, l.cells};
    for (int t : threads) {
      shape::LensFragments work = l;
      shape_match::LensPassStats stats;
      const double s = seconds_per_call(t, min_seconds, 3, [&] {
        stats = shape_match::match_lens<float>(
            cs(work.rest), {work.current.data(), work.current.size()}, cs(work.mass), list,
            {work.rotations.data(), work.rotations.size()}, settings);
      });
      ShapeLensRow row;
      row.level = level;
      row.cells = static_cast<uint32_t>(l.rest.size());
      row.fragments = list.count();
      row.threads = t;
      row.ms = s * 1e3;
      row.ns_per_cell = s * 1e9 / static_cast<double>(row.cells);
      row.fast = stats.fast;
      row.exact = stats.exact;
      row.continuous = stats.continuous;
      row.kept = stats.kept;
      rows.push_back(row);
    }
  }
  return rows;
}

}  // namespace phaco::perf
