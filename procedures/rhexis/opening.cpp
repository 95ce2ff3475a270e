#include "procedures/rhexis/opening.hpp"

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

namespace phaco::rhexis {

std::vector<uint8_t> held_triangles(const cut::CutMesh& m) {
  const Triangles& tr = m.triangles;
  const uint32_t nt = tr.slots.size();
  std::vector<uint8_t> held(nt, 0);
  std::vector<uint32_t> queue;
  for (uint32_t t = 0; t < nt; ++t) {
    if (!tr.slots.alive(t)) continue;
    for (int k = 0; k < 3; ++k)
      if (m.particles.kind[cut::corner(tr, t, k)] == ParticleKind::Anchored && !held[t])
        held[t] = 1, queue.push_back(t);
  }
  for (size_t q = 0; q < queue.size(); ++q) {
    for (uint32_t n : m.topology.adjacency.neighbour[queue[q]]) {
      if (n != kInvalidIndex && tr.slots.alive(n) && !held[n]) held[n] = 1, queue.push_back(n);
    }
  }
  return held;
}

Opening measure_opening(const cut::CutMesh& m, double pixel_mm, double field_mm) {
  Opening out;
  const Triangles& tr = m.triangles;
  const uint32_t nt = tr.slots.size();
  const std::vector<uint8_t> held = held_triangles(m);

  const int size = static_cast<int>(std::ceil(2.0 * field_mm / pixel_mm));
  cv::Mat covered(size, size, CV_8UC1, cv::Scalar(0));
  const auto px = [&](uint32_t v) {
    return cv::Point(static_cast<int>(std::lround((m.particles.x[v] + field_mm) / pixel_mm)),
                     static_cast<int>(std::lround((m.particles.y[v] + field_mm) / pixel_mm)));
  };
  for (uint32_t t = 0; t < nt; ++t) {
    if (!held[t]) continue;
    const cv::Point pts[3] = {px(tr.a[t]), px(tr.b[t]), px(tr.c[t])};
    cv::fillConvexPoly(covered, pts, 3, cv::Scalar(255), cv::LINE_8);
  }
  // The opening: the uncovered region holding the axis.
  const cv::Point centre(size / 2, size / 2);
  if (covered.at<uint8_t>(centre) != 0) return out;
  cv::Mat region = covered.clone();
  cv::floodFill(region, centre, cv::Scalar(128));
  cv::Mat hole = region == 128;
  // Open to the field's edge: the uncovered region is not enclosed.
  if (cv::countNonZero(hole.row(0)) || cv::countNonZero(hole.row(size - 1)) ||
      cv::countNonZero(hole.col(0)) || cv::countNonZero(hole.col(size - 1)))
    return out;
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(hole, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
  if (contours.empty()) return out;
  size_t biggest = 0;
  for (size_t i = 1; i < contours.size(); ++i)
    if (cv::contourArea(contours[i]) > cv::contourArea(contours[biggest])) biggest = i;
  const auto& c = contours[biggest];
  const double pixels = cv::countNonZero(hole);
  if (pixels < 16 || c.size() < 5) return out;
  out.complete = true;
  out.area_mm2 = pixels * pixel_mm * pixel_mm;
  out.diameter_mm = 2.0 * std::sqrt(out.area_mm2 / 3.14159265358979323846);
  // Perimeter: the held capsule's free edges that border the opening (both ends within a few
  // pixels of it), measured on the mesh as seen down the axis; a pixel contour would add its
  // staircase, a simplified one would cut corners.
  cv::Mat near_hole;
  cv::dilate(hole, near_hole, cv::Mat(), cv::Point(-1, -1), 3);
  const auto inside = [&](const cv::Point& p) {
    return p.x >= 0 && p.y >= 0 && p.x < size && p.y < size && near_hole.at<uint8_t>(p) != 0;
  };
  for (uint32_t t = 0; t < nt; ++t) {
    if (!held[t]) continue;
    for (int k = 0; k < 3; ++k) {
      if (m.topology.adjacency.neighbour[t][k] != kInvalidIndex) continue;
      const uint32_t u = cut::corner(tr, t, k), w = cut::corner(tr, t, (k + 1) % 3);
      if (inside(px(u)) && inside(px(w)))
        out.perimeter_mm +=
            std::hypot(m.particles.x[u] - m.particles.x[w], m.particles.y[u] - m.particles.y[w]);
    }
  }
  // A lip folded over the opening hides some of its edges from that count: the perimeter is never
  // taken shorter than the opening's own contour simplified to within a pixel (which, if anything,
  // cuts corners).
  std::vector<cv::Point> simplified;
  cv::approxPolyDP(c, simplified, 1.0, true);
  out.perimeter_mm = std::max(out.perimeter_mm, cv::arcLength(simplified, true) * pixel_mm);
  out.outline_mm.reserve(simplified.size());
  for (const cv::Point& q : simplified)
    out.outline_mm.push_back({q.x * pixel_mm - field_mm, q.y * pixel_mm - field_mm});
  out.circularity = out.perimeter_mm > 0 ? 4.0 * 3.14159265358979323846 * out.area_mm2 /
                                               (out.perimeter_mm * out.perimeter_mm)
                                         : 0.0;
  const cv::RotatedRect e = cv::fitEllipse(c);
  const double major = std::max(e.size.width, e.size.height),
               minor = std::min(e.size.width, e.size.height);
  out.ellipse_diameter_mm = 0.5 * (major + minor) * pixel_mm;
  out.ellipse_axis_ratio = major > 0 ? minor / major : 0.0;
  const cv::Moments mo = cv::moments(hole, true);
  if (mo.m00 > 0) {
    const double cx = mo.m10 / mo.m00 * pixel_mm - field_mm,
                 cy = mo.m01 / mo.m00 * pixel_mm - field_mm;
    out.centering_mm = std::hypot(cx, cy);
  }
  return out;
}

}  // namespace phaco::rhexis
