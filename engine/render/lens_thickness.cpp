#include "engine/render/lens_thickness.hpp"

#include <algorithm>
#include <cmath>

namespace phaco::render {
namespace {

constexpr int kMarginCells = 2;

// A sample exactly on an edge belongs to the triangle for which that edge is a top or left edge
// (counter-clockwise, y up): of two triangles sharing the edge, exactly one.
bool top_left(double dx, double dy) {
  return dy < 0 || (dy == 0 && dx < 0);
}

}  // namespace

void build_thickness_map(std::span<const BodyView* const> bodies, int size, ThicknessMap& map) {
  size = std::max(size, 2 * kMarginCells + 1);
  float lo_x = 1e30f, hi_x = -1e30f, lo_y = 1e30f, hi_y = -1e30f, lo_z = 1e30f, hi_z = -1e30f;
  for (const BodyView* b : bodies)
    for (size_t i = 0; i + 2 < b->xyz.size(); i += 3) {
      lo_x = std::min(lo_x, b->xyz[i]), hi_x = std::max(hi_x, b->xyz[i]);
      lo_y = std::min(lo_y, b->xyz[i + 1]), hi_y = std::max(hi_y, b->xyz[i + 1]);
      lo_z = std::min(lo_z, b->xyz[i + 2]), hi_z = std::max(hi_z, b->xyz[i + 2]);
    }
  map.size = size;
  map.mm.assign(static_cast<size_t>(size) * size, 0.0f);
  map.top_z.assign(static_cast<size_t>(size) * size, kNoSurface);
  if (lo_x > hi_x) {  // no vertices: an empty map over a unit square
    map.origin_x = map.origin_y = -0.5f;
    map.cell_mm = 1.0f / static_cast<float>(size);
    return;
  }
  const float half = std::max({0.5f * (hi_x - lo_x), 0.5f * (hi_y - lo_y), 1e-3f});
  map.cell_mm = 2 * half / static_cast<float>(size - 2 * kMarginCells);
  map.origin_x = 0.5f * (lo_x + hi_x) - half - kMarginCells * map.cell_mm;
  map.origin_y = 0.5f * (lo_y + hi_y) - half - kMarginCells * map.cell_mm;
  map.bottom_z = lo_z;
  const double cell = map.cell_mm, ox = map.origin_x, oy = map.origin_y;

  for (const BodyView* b : bodies) {
    const float* x = b->xyz.data();
    const size_t n = b->xyz.size() / 3;
    for (size_t t = 0; t + 2 < b->tris.size(); t += 3) {
      uint32_t i0 = b->tris[t], i1 = b->tris[t + 1], i2 = b->tris[t + 2];
      if (i0 >= n || i1 >= n || i2 >= n) continue;
      const double area2 =
          (double{x[3 * i1]} - x[3 * i0]) * (double{x[3 * i2 + 1]} - x[3 * i0 + 1]) -
          (double{x[3 * i1 + 1]} - x[3 * i0 + 1]) * (double{x[3 * i2]} - x[3 * i0]);
      if (area2 == 0) continue;  // seen edge-on: no line enters through it
      // Facing the microscope (+z, counter-clockwise seen from above) enters the lens: +z.
      const double sign = area2 > 0 ? 1.0 : -1.0;
      if (area2 < 0) std::swap(i1, i2);  // counter-clockwise for the edge tests
      const double ax = x[3 * i0], ay = x[3 * i0 + 1], az = x[3 * i0 + 2];
      const double bx = x[3 * i1], by = x[3 * i1 + 1], bz = x[3 * i1 + 2];
      const double cx = x[3 * i2], cy = x[3 * i2 + 1], cz = x[3 * i2 + 2];
      const double inv_area = 1.0 / std::abs(area2);
      const int c0 =
          std::max(0, static_cast<int>(std::ceil((std::min({ax, bx, cx}) - ox) / cell - 0.5)));
      const int c1 = std::min(
          size - 1, static_cast<int>(std::floor((std::max({ax, bx, cx}) - ox) / cell - 0.5)));
      const int r0 =
          std::max(0, static_cast<int>(std::ceil((std::min({ay, by, cy}) - oy) / cell - 0.5)));
      const int r1 = std::min(
          size - 1, static_cast<int>(std::floor((std::max({ay, by, cy}) - oy) / cell - 0.5)));
      for (int r = r0; r <= r1; ++r) {
        const double py = oy + (r + 0.5) * cell;
        for (int c = c0; c <= c1; ++c) {
          const double px = ox + (c + 0.5) * cell;
          // Edge functions: twice the signed areas opposite each corner.
          const double wa = (cx - bx) * (py - by) - (cy - by) * (px - bx);
          const double wb = (ax - cx) * (py - cy) - (ay - cy) * (px - cx);
          const double wc = (bx - ax) * (py - ay) - (by - ay) * (px - ax);
          if (wa < 0 || wb < 0 || wc < 0) continue;
          if ((wa == 0 && !top_left(cx - bx, cy - by)) ||
              (wb == 0 && !top_left(ax - cx, ay - cy)) || (wc == 0 && !top_left(bx - ax, by - ay)))
            continue;
          const double z = (wa * az + wb * bz + wc * cz) * inv_area;
          const size_t cell_index = static_cast<size_t>(r) * size + c;
          map.mm[cell_index] += static_cast<float>(sign * z);
          if (sign > 0)
            map.top_z[cell_index] = std::max(map.top_z[cell_index], static_cast<float>(z));
        }
      }
    }
  }
  const float most = hi_z - lo_z;
  for (float& v : map.mm) v = std::clamp(v, 0.0f, most);
}

float thickness_at(const ThicknessMap& map, float x, float y) {
  if (map.size == 0) return 0;
  const float u = (x - map.origin_x) / map.cell_mm - 0.5f;
  const float v = (y - map.origin_y) / map.cell_mm - 0.5f;
  const int c = static_cast<int>(std::floor(u)), r = static_cast<int>(std::floor(v));
  const float fu = u - static_cast<float>(c), fv = v - static_cast<float>(r);
  auto at = [&](int cc, int rr) {
    if (cc < 0 || rr < 0 || cc >= map.size || rr >= map.size) return 0.0f;
    return map.mm[static_cast<size_t>(rr) * map.size + cc];
  };
  return (1 - fv) * ((1 - fu) * at(c, r) + fu * at(c + 1, r)) +
         fv * ((1 - fu) * at(c, r + 1) + fu * at(c + 1, r + 1));
}

}  // namespace phaco::render
