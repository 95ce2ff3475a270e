#include "procedures/trainer/pointer_clutch.hpp"

#include <cmath>

namespace phaco {

std::array<double, 2> clutch_step(PointerClutch& c, double x, double y, bool in_view, bool held) {
  const bool engaged = in_view && !held && std::isfinite(x) && std::isfinite(y);
  std::array<double, 2> d{0.0, 0.0};
  // Motion counts only between two engaged positions: the step onto a panel, off the window or
  // back into the view is the pointer's alone.
  if (engaged && c.have_last && c.engaged_last) d = {x - c.last_x, y - c.last_y};
  c.have_last = std::isfinite(x) && std::isfinite(y);
  c.engaged_last = engaged;
  if (c.have_last) c.last_x = x, c.last_y = y;
  return d;
}

}  // namespace phaco
