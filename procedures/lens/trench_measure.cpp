#include "procedures/lens/trench_measure.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <stdexcept>

namespace phaco::lens {
namespace {

constexpr double kPi = 3.14159265358979323846;

struct Axis2 {
  Vec3 centre = Vec3::Zero();
  Vec3 dir = Vec3::UnitX();
  double volume = 0;
};

// Volume-weighted centre and principal direction in the iris plane.
Axis2 principal_axis(std::span<const RemovedElement* const> elems) {
  Axis2 a;
  for (const RemovedElement* e : elems) {
    a.centre += e->volume_mm3 * e->centre;
    a.volume += e->volume_mm3;
  }
  if (a.volume <= 0) return a;
  a.centre /= a.volume;
  double sxx = 0, sxy = 0, syy = 0;
  for (const RemovedElement* e : elems) {
    const double dx = e->centre.x() - a.centre.x(), dy = e->centre.y() - a.centre.y();
    sxx += e->volume_mm3 * dx * dx, sxy += e->volume_mm3 * dx * dy, syy += e->volume_mm3 * dy * dy;
  }
  // Major eigenvector of [[sxx, sxy], [sxy, syy]]: angle ½·atan2(2 sxy, sxx − syy).
  const double angle = 0.5 * std::atan2(2 * sxy, sxx - syy);
  a.dir = Vec3(std::cos(angle), std::sin(angle), 0);
  return a;
}

// Weighted percentile q ∈ [0, 1] of (value, weight) pairs.
double percentile(std::vector<std::pair<double, double>>& vw, double q) {
  std::sort(vw.begin(), vw.end());
  double total = 0;
  for (const auto& p : vw) total += p.second;
  double acc = 0;
  for (const auto& p : vw) {
    acc += p.second;
    if (acc >= q * total) return p.first;
  }
  return vw.empty() ? 0.0 : vw.back().first;
}

double angle_between_deg(const Vec3& a, const Vec3& b) {
  const double c = std::min(1.0, std::abs(a.dot(b)));  // axes are lines: sign does not matter
  return std::acos(c) * 180.0 / kPi;
}

double distance_to_line(const Vec3& p, const Axis2& line) {
  const Vec3 d = p - line.centre;
  return std::abs(d.x() * line.dir.y() - d.y() * line.dir.x());
}

uint32_t find(std::vector<uint32_t>& parent, uint32_t i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

}  // namespace

double nucleus_anterior_z(const NucleusShape& n, double x, double y) {
  const double s = 1.0 - (x * x + y * y) / (n.equatorial_radius_mm * n.equatorial_radius_mm);
  return s < 0 ? std::numeric_limits<double>::quiet_NaN() : n.anterior_mm * std::sqrt(s);
}

double nucleus_posterior_z(const NucleusShape& n, double x, double y) {
  const double s = 1.0 - (x * x + y * y) / (n.equatorial_radius_mm * n.equatorial_radius_mm);
  return s < 0 ? std::numeric_limits<double>::quiet_NaN() : n.posterior_mm * std::sqrt(s);
}

TrenchReport measure_trenches(std::span<const RemovedElement> removed, const NucleusShape& nucleus,
                              const TrenchSettings& settings) {
  if (!(nucleus.equatorial_radius_mm > 0 && nucleus.anterior_mm > 0 && nucleus.posterior_mm < 0)) {
    throw std::invalid_argument(
        "measure_trenches: nucleus radius and anterior pole must be > 0, posterior pole < 0");
  }
  TrenchReport report;
  std::map<uint32_t, std::vector<const RemovedElement*>> by_stroke;
  for (const RemovedElement& e : removed) {
    by_stroke[e.stroke].push_back(&e);
    report.volume_removed_mm3 += e.volume_mm3;
  }
  std::vector<uint32_t> stroke_ids;
  std::vector<Axis2> axes;
  for (const auto& [id, elems] : by_stroke) {
    Axis2 a = principal_axis(elems);
    if (a.volume < settings.min_stroke_volume_mm3) continue;
    stroke_ids.push_back(id);
    axes.push_back(a);
  }
  // Strokes that run the same way along the same line are one trench.
  std::vector<uint32_t> parent(axes.size());
  std::iota(parent.begin(), parent.end(), 0u);
  for (uint32_t i = 0; i < axes.size(); ++i) {
    for (uint32_t j = i + 1; j < axes.size(); ++j) {
      if (angle_between_deg(axes[i].dir, axes[j].dir) > settings.same_direction_deg) continue;
      if (std::min(distance_to_line(axes[i].centre, axes[j]),
                   distance_to_line(axes[j].centre, axes[i])) > settings.same_line_mm)
        continue;
      parent[find(parent, j)] = find(parent, i);
    }
  }
  std::map<uint32_t, std::vector<uint32_t>> groups;  // root -> indices into stroke_ids
  for (uint32_t i = 0; i < axes.size(); ++i) groups[find(parent, i)].push_back(i);

  for (const auto& [root, members] : groups) {
    std::vector<const RemovedElement*> elems;
    Trench t;
    for (uint32_t m : members) {
      const auto& s = by_stroke[stroke_ids[m]];
      elems.insert(elems.end(), s.begin(), s.end());
      t.strokes.push_back(stroke_ids[m]);
    }
    const Axis2 a = principal_axis(elems);
    t.axis = a.dir;
    t.centre = a.centre;
    t.volume_mm3 = a.volume;
    std::vector<std::pair<double, double>> across, along;
    across.reserve(elems.size()), along.reserve(elems.size());
    const Vec3 normal(-a.dir.y(), a.dir.x(), 0);
    for (const RemovedElement* e : elems) {
      const Vec3 d = e->centre - a.centre;
      across.push_back({d.dot(normal), e->volume_mm3});
      along.push_back({d.dot(a.dir), e->volume_mm3});
    }
    t.width_mm = (percentile(across, 0.95) - percentile(across, 0.05)) / 0.9;
    t.length_mm = (percentile(along, 0.95) - percentile(along, 0.05)) / 0.9;

    // Depth where the trench passes the lens axis (where a surgeon judges it); if it does not
    // pass near the axis, at its own centre.
    std::vector<std::pair<double, double>> core_z;
    auto collect = [&](double cx, double cy) {
      core_z.clear();
      for (const RemovedElement* e : elems) {
        if (std::hypot(e->centre.x() - cx, e->centre.y() - cy) <= settings.core_radius_mm)
          core_z.push_back({e->centre.z(), e->volume_mm3});
      }
    };
    double cx = 0, cy = 0;
    collect(cx, cy);
    if (core_z.empty()) cx = a.centre.x(), cy = a.centre.y(), collect(cx, cy);
    if (!core_z.empty()) {
      const double z_deep = percentile(core_z, 0.02);
      const double top = nucleus_anterior_z(nucleus, cx, cy),
                   bottom = nucleus_posterior_z(nucleus, cx, cy);
      if (std::isfinite(top) && std::isfinite(bottom)) {
        t.depth_mm = std::max(0.0, top - z_deep);
        t.depth_fraction = t.depth_mm / (top - bottom);
      }
    }
    report.trenches.push_back(std::move(t));
  }
  std::sort(report.trenches.begin(), report.trenches.end(),
            [](const Trench& x, const Trench& y) { return x.volume_mm3 > y.volume_mm3; });
  if (report.trenches.size() >= 2) {
    report.crossing_angle_deg = angle_between_deg(report.trenches[0].axis, report.trenches[1].axis);
  }
  return report;
}

}  // namespace phaco::lens
