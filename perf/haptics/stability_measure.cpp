// Measurements of the local haptic force model: see stability_measure.hpp.
#include "perf/haptics/stability_measure.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>

#include "systems/haptic_model/haptic_model.hpp"

namespace phaco::perf {
namespace {

using haptic_model::HapticForce;
using haptic_model::HapticSettings;
using haptic_model::HapticToolState;

constexpr double kPi = 3.14159265358979323846;

uint16_t add_node(HapticTool& t, double x, double y, double z, HapticNodeKind kind, double mass) {
  const uint32_t i = t.node_count++;
  t.x[i] = float(x), t.y[i] = float(y), t.z[i] = float(z), t.mass[i] = float(mass),
  t.kind[i] = kind;
  return uint16_t(i);
}

void add_spring(HapticTool& t, uint16_t i, uint16_t j, double k, double rest) {
  if (t.spring_count >= kHapticMaxSprings) return;
  const uint32_t s = t.spring_count++;
  t.spring_i[s] = i, t.spring_j[s] = j, t.k_mn_per_mm[s] = float(k), t.rest_mm[s] = float(rest);
}

// Two anchored triangles: the square [-5, 5]² in z = 0, rigid contact.
std::unique_ptr<HapticTool> wall() {
  auto t = std::make_unique<HapticTool>();
  t->present = true;
  t->tip_mm = {0, 0, 1};
  add_node(*t, -5, -5, 0, HapticNodeKind::Anchored, 0);
  add_node(*t, 5, -5, 0, HapticNodeKind::Anchored, 0);
  add_node(*t, 5, 5, 0, HapticNodeKind::Anchored, 0);
  add_node(*t, -5, 5, 0, HapticNodeKind::Anchored, 0);
  t->triangle_count = 2;
  t->triangles[0] = {0, 1, 2};
  t->triangles[1] = {0, 2, 3};
  return t;
}

// nx × ny sheet in z = z0, rim anchored, grid springs plus one diagonal per cell, rest lengths
// shortened by `prestretch`; the triangles of the cells nearest the centre, up to the patch cap.
std::unique_ptr<HapticTool> sheet(int nx, int ny, double spacing, double k, double prestretch,
                                  double z0, double damping) {
  auto t = std::make_unique<HapticTool>();
  t->present = true;
  const double hx = 0.5 * spacing * (nx - 1), hy = 0.5 * spacing * (ny - 1);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const bool rim = i == 0 || j == 0 || i == nx - 1 || j == ny - 1;
      add_node(*t, i * spacing - hx, j * spacing - hy, z0,
               rim ? HapticNodeKind::Anchored : HapticNodeKind::Free, 1e-10);
    }
  auto id = [nx](int i, int j) { return uint16_t(j * nx + i); };
  std::vector<std::pair<double, std::pair<int, int>>> cells;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      if (i + 1 < nx) add_spring(*t, id(i, j), id(i + 1, j), k, spacing / (1 + prestretch));
      if (j + 1 < ny) add_spring(*t, id(i, j), id(i, j + 1), k, spacing / (1 + prestretch));
      if (i + 1 < nx && j + 1 < ny) {
        add_spring(*t, id(i, j), id(i + 1, j + 1), k, spacing * std::sqrt(2.0) / (1 + prestretch));
        const double cx = (i + 0.5) * spacing - hx, cy = (j + 0.5) * spacing - hy;
        cells.push_back({cx * cx + cy * cy, {i, j}});
      }
    }
  std::stable_sort(cells.begin(), cells.end(), [](auto& a, auto& b) { return a.first < b.first; });
  for (const auto& c : cells) {
    if (t->triangle_count + 2 > kHapticMaxTriangles) break;
    const int i = c.second.first, j = c.second.second;
    t->triangles[t->triangle_count++] = {id(i, j), id(i + 1, j), id(i + 1, j + 1)};
    t->triangles[t->triangle_count++] = {id(i, j), id(i + 1, j + 1), id(i, j + 1)};
  }
  t->damping_mn_s_per_mm = float(damping);
  t->tip_mm = {0.1f, 0.1f, float(z0 + 1.0)};
  return t;
}

// Device of mass m, damping b, constant user force; force sampled and held (zero-order hold);
// returns late-window over early-window peak of the oscillation energy about `rest` (stiffness k).
double energy_growth(const HapticTool& model, const HapticSettings& s, double m, double b,
                     const Vec3& user, const Vec3& rest, double k_energy, const Vec3& x0,
                     double seconds) {
  auto st = std::make_unique<HapticToolState>();
  haptic_model::adopt_model(model, *st, s);
  Vec3 x = x0, v = Vec3::Zero(), prev = x0;
  const int ticks = int(seconds / s.dt_s), substeps = 40;
  const double h = s.dt_s / substeps;
  std::vector<double> e(ticks);
  for (int k = 0; k < ticks; ++k) {
    const HapticForce f =
        haptic_model::haptic_tick(st->newest_model(), x, (x - prev) / s.dt_s, s, *st);
    prev = x;
    e[k] = 0.5 * m * v.squaredNorm() + 0.5 * k_energy * (x - rest).squaredNorm();
    for (int j = 0; j < substeps; ++j) {
      v = (v + h / m * (f.force_mn + user)) / (1 + h * b / m);
      x += h * v;
    }
  }
  const int win = ticks / 6;
  const double early = *std::max_element(e.begin(), e.begin() + win);
  const double late = *std::max_element(e.end() - win, e.end());
  return late / early;
}

// Largest K in [lo, hi] (log bisection) for which passive(K) holds; passive(lo) assumed.
template <class F>
double bisect_limit(double lo, double hi, F&& passive) {
  for (int it = 0; it < 14; ++it) {
    const double mid = std::sqrt(lo * hi);
    (passive(mid) ? lo : hi) = mid;
  }
  return lo;
}

// Continuity scenario of the unit test: the simulation's sheet rises and falls with its rim,
// models published at `model_hz` (the sheet as the haptic side has it deformed, moved with the
// rim), an optional 200 ms stall; the device presses and circles.
ContinuityRow continuity(double model_hz, bool stall, bool crossfade) {
  HapticSettings s;
  s.blend_ms = crossfade ? 4.0 : 0.0;
  s.blend_max_step_mn = crossfade ? 0.25 : 0.0;
  auto st = std::make_unique<HapticToolState>();
  std::unique_ptr<HapticTool> model;
  bool started = false;
  auto sim_z = [](double t) { return 0.15 * std::sin(2 * kPi * 1.3 * t); };
  double next_model = 0, fmin = 1e300, fmax = -1e300, jump = 0;
  Vec3 last = Vec3::Zero();
  const double period = 1.0 / model_hz;
  for (int k = 0; k < 1500; ++k) {
    const double t = k * s.dt_s;
    if (t >= next_model && !(stall && t > 0.6 && t < 0.8)) {
      const double z0 = sim_z(t);
      auto next = sheet(9, 9, 0.5, 40, 0.2, z0, 0.1);
      if (started) {
        const auto& now = st->slot[st->newest];
        const double shift = z0 - now.model.z[0];
        for (uint32_t i = 0; i < next->node_count; ++i) {
          next->x[i] = float(now.x[i]), next->y[i] = float(now.y[i]),
          next->z[i] = float(now.z[i] + shift);
        }
      }
      model = std::move(next);
      haptic_model::adopt_model(*model, *st, s);
      started = true;
      while (next_model <= t) next_model += period;
    }
    const Vec3 dev(0.6 * std::cos(2 * kPi * 0.7 * t), 0.6 * std::sin(2 * kPi * 0.7 * t),
                   0.3 - 0.55 * std::min(1.0, t / 0.2) - 0.15 * std::sin(2 * kPi * 0.9 * t));
    const HapticForce f = haptic_model::haptic_tick(st->newest_model(), dev, Vec3::Zero(), s, *st);
    if (k > 0) jump = std::max(jump, (f.force_mn - last).norm());
    last = f.force_mn;
    fmin = std::min(fmin, f.force_mn.z()), fmax = std::max(fmax, f.force_mn.z());
  }
  ContinuityRow row;
  row.crossfade = crossfade;
  row.range_mn = fmax - fmin;
  row.max_jump_mn = jump;
  row.jump_fraction = row.range_mn > 0 ? jump / row.range_mn : 0;
  return row;
}

}  // namespace

std::vector<StiffnessLimitRow> measure_stiffness_limits(std::vector<double> rates_hz) {
  if (rates_hz.empty()) rates_hz = {250, 500, 1000, 2000, 4000};
  std::vector<StiffnessLimitRow> rows;
  const double m = 0.05;
  for (double rate : rates_hz) {
    HapticSettings s;
    s.dt_s = 1.0 / rate;
    {  // wall: pushed with 300 mN, started 0.02 mm off its rest point
      const double b = 1.0, bound = 2 * b * rate;
      auto w = wall();
      const double r = w->tip_radius_mm;
      auto passive = [&](double k) {
        s.coupling_stiffness_mn_per_mm = k;
        const double kser = k * 1000.0 / 1001.0, z_eq = r - 300.0 / kser;
        return energy_growth(*w, s, m, b, Vec3(0, 0, -300), Vec3(0, 0, z_eq), kser,
                             Vec3(0, 0, z_eq + 0.02), 0.6) < 1.0;
      };
      rows.push_back({"wall", rate, m, b, bisect_limit(0.05 * bound, 20 * bound, passive), bound});
    }
    {  // grasped membrane: the middle node of a 5 × 5 sheet, pulled 0.05 mm sideways and released
      const double b = 0.1, bound = 2 * b * rate;
      s.coupling_stiffness_mn_per_mm = 200 * bound;
      double k_eff_at_limit = 0;
      auto passive = [&](double spring_k) {
        auto g = sheet(5, 5, 0.5, spring_k, 0.05, 0.0, 0.0);
        g->grasped_node = 12;
        g->kind[12] = HapticNodeKind::Grasped;
        const Vec3 rest(g->x[12], g->y[12], g->z[12]);
        // Its stiffness at the grasped node, from a static pull.
        auto st = std::make_unique<HapticToolState>();
        haptic_model::adopt_model(*g, *st, s);
        HapticForce f;
        for (int k = 0; k < 400; ++k)
          f = haptic_model::haptic_tick(*g, rest + Vec3(0.01, 0, 0), Vec3::Zero(), s, *st);
        const double k_eff = -f.force_mn.x() / 0.01;
        const bool ok = energy_growth(*g, s, m, b, Vec3::Zero(), rest, k_eff,
                                      rest + Vec3(0.05, 0, 0), 0.6) < 1.0;
        if (ok) k_eff_at_limit = k_eff;
        return ok;
      };
      bisect_limit(0.01 * bound, 10 * bound, passive);
      rows.push_back({"grasped membrane", rate, m, b, k_eff_at_limit, bound});
    }
  }
  return rows;
}

std::vector<ContinuityRow> measure_continuity() {
  std::vector<ContinuityRow> rows;
  struct Case {
    const char* name;
    double hz;
    bool stall;
  };
  for (const Case& c : {Case{"120 Hz", 120, false}, Case{"30 Hz", 30, false},
                        Case{"30 Hz + 200 ms stall", 30, true}}) {
    for (bool crossfade : {true, false}) {
      ContinuityRow row = continuity(c.hz, c.stall, crossfade);
      row.models = c.name;
      rows.push_back(row);
    }
  }
  return rows;
}

std::vector<TickCostRow> measure_tick_cost(std::vector<uint32_t> node_counts, uint64_t ticks) {
  if (node_counts.empty()) node_counts = {0, 64, 121, 256, 384};
  using Clock = std::chrono::steady_clock;
  auto ns_since = [](Clock::time_point t0) {
    return double(std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - t0).count());
  };
  std::vector<TickCostRow> rows;
  for (uint32_t n : node_counts) {
    std::unique_ptr<HapticTool> model;
    if (n == 0) {
      model = wall();
    } else {  // the most nearly square grid of n nodes (64 = 8², 121 = 11², 256 = 16², 384 = 16 ×
              // 24)
      int nx = int(std::sqrt(double(n)));
      while (nx > 1 && n % nx) --nx;
      model = sheet(nx, int(n / nx), 0.5, 40, 0.2, 0.0, 0.1);
    }
    HapticSettings s;
    auto st = std::make_unique<HapticToolState>();
    haptic_model::adopt_model(*model, *st, s);
    std::vector<double> times;
    times.reserve(ticks);
    double iterations = 0;
    for (uint64_t k = 0; k < ticks; ++k) {
      const double t = k * s.dt_s;
      const Vec3 dev(0.5 * std::cos(2 * kPi * 0.5 * t), 0.5 * std::sin(2 * kPi * 0.5 * t),
                     0.15 - 0.2 - 0.1 * std::sin(2 * kPi * 0.8 * t));
      const auto t0 = Clock::now();
      const HapticForce f =
          haptic_model::haptic_tick(st->newest_model(), dev, Vec3::Zero(), s, *st);
      times.push_back(ns_since(t0));
      iterations += f.solver_iterations;
    }
    TickCostRow row;
    row.nodes = model->node_count, row.springs = model->spring_count,
    row.triangles = model->triangle_count;
    row.ticks = ticks;
    double sum = 0;
    for (double x : times) sum += x;
    row.mean_ns = sum / double(times.size());
    row.mean_cg_iterations = iterations / double(ticks);
    std::sort(times.begin(), times.end());
    row.p99_ns = times[size_t(0.99 * double(times.size() - 1))];
    row.max_ns = times.back();
    // Adopting a model, and the tick right after it (both models ticked).
    const int adopts = 300;
    double adopt_ns = 0, blend_ns = 0;
    for (int a = 0; a < adopts; ++a) {
      auto t0 = Clock::now();
      haptic_model::adopt_model(*model, *st, s);
      adopt_ns += ns_since(t0);
      t0 = Clock::now();
      haptic_model::haptic_tick(st->newest_model(), Vec3(0.1, 0.1, -0.05), Vec3::Zero(), s, *st);
      blend_ns += ns_since(t0);
    }
    row.adopt_mean_ns = adopt_ns / adopts;
    row.blend_mean_ns = blend_ns / adopts;
    rows.push_back(row);
  }
  return rows;
}

}  // namespace phaco::perf
