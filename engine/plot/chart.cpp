#include "engine/plot/chart.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace phaco::plot {

namespace {

// Layout in pixels: plot area inside these margins, legend in the right margin.
constexpr int kLeft = 100, kTop = 56, kBottom = 70, kLegendWidth = 270;
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;

const cv::Scalar kPalette[] = {
    {180, 119, 31}, {14, 127, 255},  {44, 160, 44},   {40, 39, 214},  {189, 103, 148},
    {75, 86, 140},  {194, 119, 227}, {127, 127, 127}, {34, 189, 188}, {207, 190, 23},
};
constexpr size_t kPaletteSize = sizeof(kPalette) / sizeof(kPalette[0]);
const cv::Scalar kInk(40, 40, 40), kGrid(225, 225, 225), kWhite(255, 255, 255);

bool finite(double v) {
  return std::isfinite(v);
}

std::string tick_label(double v) {
  char buf[32];
  const double a = std::fabs(v);
  if (v == 0) return "0";
  if (a >= 1e5 || a < 1e-3) {
    const int e = static_cast<int>(std::floor(std::log10(a) + 1e-9));
    const double m = v / std::pow(10.0, e);
    if (std::fabs(m - std::round(m)) < 1e-6)
      std::snprintf(buf, sizeof buf, "%.0fe%d", m, e);
    else
      std::snprintf(buf, sizeof buf, "%.1fe%d", m, e);
  } else {
    std::snprintf(buf, sizeof buf, "%g", v);
  }
  return buf;
}

// Step of 1, 2 or 5 × 10^k giving about `target` intervals over span.
double nice_step(double span, int target) {
  const double raw = span / target;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (m * mag >= raw) return m * mag;
  }
  return 10 * mag;
}

void draw_marker(cv::Mat& img, cv::Point p, size_t shape, const cv::Scalar& c) {
  constexpr int r = 4;
  switch (shape % 4) {
    case 0:
      cv::circle(img, p, r, c, cv::FILLED, cv::LINE_AA);
      break;
    case 1:
      cv::rectangle(img, p - cv::Point(r, r), p + cv::Point(r, r), c, cv::FILLED);
      break;
    case 2: {
      const cv::Point tri[3] = {p + cv::Point(0, -r - 1), p + cv::Point(r + 1, r),
                                p + cv::Point(-r - 1, r)};
      cv::fillConvexPoly(img, tri, 3, c, cv::LINE_AA);
      break;
    }
    default:
      cv::line(img, p - cv::Point(r, r), p + cv::Point(r, r), c, 2, cv::LINE_AA);
      cv::line(img, p - cv::Point(r, -r), p + cv::Point(r, -r), c, 2, cv::LINE_AA);
  }
}

void dashed_line(cv::Mat& img, cv::Point2d a, cv::Point2d b, const cv::Scalar& c, int thickness) {
  const double len = std::hypot(b.x - a.x, b.y - a.y);
  if (len < 1) return;
  const int n = std::max(1, static_cast<int>(len / 8));
  for (int k = 0; k < n; k += 2) {
    const double t0 = static_cast<double>(k) / n,
                 t1 = std::min(1.0, static_cast<double>(k + 1) / n);
    cv::line(img, a + (b - a) * t0, a + (b - a) * t1, c, thickness, cv::LINE_AA);
  }
}

void text(cv::Mat& img, const std::string& s, cv::Point at, double scale, const cv::Scalar& c,
          int thick = 1) {
  cv::putText(img, s, at, kFont, scale, c, thick, cv::LINE_AA);
}

int text_width(const std::string& s, double scale, int thick = 1) {
  int base = 0;
  return cv::getTextSize(s, kFont, scale, thick, &base).width;
}

// Shortens s with "..." until it fits max_px.
std::string fit_text(std::string s, double scale, int max_px) {
  if (text_width(s, scale) <= max_px) return s;
  while (s.size() > 4 && text_width(s + "...", scale) > max_px) s.pop_back();
  return s + "...";
}

}  // namespace

PowerFit fit_power_law(std::span<const double> x, std::span<const double> y) {
  PowerFit fit;
  const size_t n = std::min(x.size(), y.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0;
  for (size_t i = 0; i < n; ++i) {
    if (!(finite(x[i]) && finite(y[i]) && x[i] > 0 && y[i] > 0)) continue;
    const double lx = std::log(x[i]), ly = std::log(y[i]);
    sx += lx, sy += ly, sxx += lx * lx, sxy += lx * ly, syy += ly * ly;
    ++fit.points;
  }
  if (fit.points < 2) return fit;
  const double m = static_cast<double>(fit.points);
  const double vxx = sxx - sx * sx / m, vxy = sxy - sx * sy / m, vyy = syy - sy * sy / m;
  if (!(vxx > 1e-300)) return fit;
  fit.ok = true;
  fit.slope = vxy / vxx;
  fit.coefficient = std::exp((sy - fit.slope * sx) / m);
  fit.r2 = vyy > 0 ? (vxy * vxy) / (vxx * vyy) : 1.0;
  return fit;
}

bool AxisMap::usable(double v) const {
  return finite(v) && (scale == Scale::Linear || v > 0);
}

double AxisMap::to_pixel(double v) const {
  const double t = scale == Scale::Log10
                       ? (std::log10(v) - std::log10(lo)) / (std::log10(hi) - std::log10(lo))
                       : (v - lo) / (hi - lo);
  return p0 + t * (p1 - p0);
}

std::optional<std::pair<double, double>> axis_range(const Axis& axis,
                                                    std::span<const double> values) {
  const bool log = axis.scale == Scale::Log10;
  double lo = INFINITY, hi = -INFINITY;
  for (double v : values) {
    if (!finite(v) || (log && v <= 0)) continue;
    lo = std::min(lo, v), hi = std::max(hi, v);
  }
  if (axis.min && (!log || *axis.min > 0)) lo = *axis.min;
  if (axis.max && (!log || *axis.max > 0)) hi = *axis.max;
  if (!(lo <= hi)) return std::nullopt;
  if (log) {
    if (!axis.min) lo = std::pow(10.0, std::floor(std::log10(lo) + 1e-9));
    if (!axis.max) hi = std::pow(10.0, std::ceil(std::log10(hi) - 1e-9));
    if (hi <= lo) hi = lo * 10;
    return std::pair{lo, hi};
  }
  if (hi == lo) {
    const double pad = lo == 0 ? 1.0 : std::fabs(lo) * 0.1;
    lo -= pad, hi += pad;
  }
  const double step = nice_step(hi - lo, 6);
  if (!axis.min) lo = std::floor(lo / step + 1e-9) * step;
  if (!axis.max) hi = std::ceil(hi / step - 1e-9) * step;
  return std::pair{lo, hi};
}

std::vector<double> axis_ticks(double lo, double hi, Scale scale) {
  std::vector<double> ticks;
  if (!(lo < hi) || !finite(lo) || !finite(hi)) return ticks;
  if (scale == Scale::Log10) {
    if (lo <= 0) return ticks;
    const int e0 = static_cast<int>(std::floor(std::log10(lo) + 1e-9));
    const int e1 = static_cast<int>(std::ceil(std::log10(hi) - 1e-9));
    const int stride = std::max(1, (e1 - e0 + 9) / 10);  // at most ~10 labelled decades
    const bool minor = std::log10(hi / lo) < 2.0 - 1e-9;
    static constexpr double kMantissas[] = {1, 2, 5};
    const size_t mantissas = minor ? 3 : 1;
    for (int e = e0; e <= e1; e += stride) {
      for (size_t k = 0; k < mantissas; ++k) {
        const double v = kMantissas[k] * std::pow(10.0, e);
        if (v >= lo * (1 - 1e-9) && v <= hi * (1 + 1e-9)) ticks.push_back(v);
      }
    }
    return ticks;
  }
  const double step = nice_step(hi - lo, 6);
  for (double v = std::ceil(lo / step - 1e-9) * step; v <= hi + step * 1e-9; v += step) {
    ticks.push_back(std::fabs(v) < step * 1e-9 ? 0.0 : v);
  }
  return ticks;
}

std::vector<size_t> pareto_indices(std::span<const double> x, std::span<const double> y) {
  std::vector<size_t> order;
  for (size_t i = 0; i < std::min(x.size(), y.size()); ++i) {
    if (finite(x[i]) && finite(y[i])) order.push_back(i);
  }
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return x[a] != x[b] ? x[a] < x[b] : y[a] < y[b]; });
  std::vector<size_t> front;
  double best_y = INFINITY;
  for (size_t i : order) {
    if (y[i] < best_y) {
      front.push_back(i);
      best_y = y[i];
    }
  }
  return front;
}

namespace {

// The plot box in pixels and the axes' maps, shared by the drawing steps below.
struct PlotArea {
  cv::Mat& img;
  const Chart& chart;
  int w, h, px0, px1, py0, py1;
  bool usable_x(double v) const { return finite(v) && (chart.x.scale == Scale::Linear || v > 0); }
  bool usable_y(double v) const { return finite(v) && (chart.y.scale == Scale::Linear || v > 0); }
};

struct PlotMaps {
  AxisMap mx, my;
  int px0, px1, py0, py1;
  bool in_box(double px, double py) const {
    return px >= px0 - 1 && px <= px1 + 1 && py >= py1 - 1 && py <= py0 + 1;
  }
};

// The values that size the axes: every drawable point and marker; warns of the others.
void gather_values(const PlotArea& a, std::vector<double>& xs, std::vector<double>& ys,
                   RenderReport& report) {
  for (const Series& s : a.chart.series) {
    const size_t n = std::min(s.x.size(), s.y.size());
    if (s.x.size() != s.y.size()) {
      report.warnings.push_back("series '" + s.name +
                                "': x and y lengths differ, extra points ignored");
    }
    size_t skipped = 0;
    for (size_t i = 0; i < n; ++i) {
      if (a.usable_x(s.x[i]) && a.usable_y(s.y[i])) {
        xs.push_back(s.x[i]), ys.push_back(s.y[i]);
      } else {
        ++skipped;
      }
    }
    report.points_skipped += skipped;
    if (n == 0)
      report.warnings.push_back("series '" + s.name + "' is empty");
    else if (skipped) {
      report.warnings.push_back("series '" + s.name + "': " + std::to_string(skipped) +
                                " point(s) skipped (NaN, infinite, or not positive on a log axis)");
    }
  }
  for (const Marker& m : a.chart.markers) {
    if (a.usable_x(m.x) && a.usable_y(m.y))
      xs.push_back(m.x), ys.push_back(m.y);
    else
      report.warnings.push_back("marker '" + m.label + "' skipped (not drawable on these axes)");
  }
}

// Title, axis labels (the y label turned upright) and the box.
void draw_labels(const PlotArea& a) {
  cv::Mat& img = a.img;
  text(img, fit_text(a.chart.title, 0.7, a.w - 20), {kLeft, 34}, 0.7, kInk, 2);
  const std::string xl = fit_text(a.chart.x.label, 0.55, a.px1 - a.px0);
  text(img, xl, {(a.px0 + a.px1 - text_width(xl, 0.55)) / 2, a.h - 18}, 0.55, kInk);
  const std::string yl = fit_text(a.chart.y.label, 0.55, a.py0 - a.py1);
  cv::Mat label(24, std::max(1, text_width(yl, 0.55) + 4), CV_8UC3, kWhite);
  text(label, yl, {2, 17}, 0.55, kInk);
  cv::Mat rotated;
  cv::rotate(label, rotated, cv::ROTATE_90_COUNTERCLOCKWISE);
  const int top = std::clamp((a.py0 + a.py1 - rotated.rows) / 2, 0, a.h - rotated.rows);
  rotated.copyTo(img(cv::Rect(8, top, rotated.cols, rotated.rows)));
  cv::rectangle(img, {a.px0, a.py1}, {a.px1, a.py0}, kInk, 1);
}

void draw_grid(const PlotArea& a, const PlotMaps& m) {
  cv::Mat& img = a.img;
  for (double t : axis_ticks(m.mx.lo, m.mx.hi, m.mx.scale)) {
    const int p = static_cast<int>(std::lround(m.mx.to_pixel(t)));
    cv::line(img, {p, a.py1}, {p, a.py0}, kGrid, 1);
    cv::line(img, {p, a.py0}, {p, a.py0 + 5}, kInk, 1);
    const std::string s = tick_label(t);
    text(img, s, {p - text_width(s, 0.45) / 2, a.py0 + 22}, 0.45, kInk);
  }
  for (double t : axis_ticks(m.my.lo, m.my.hi, m.my.scale)) {
    const int p = static_cast<int>(std::lround(m.my.to_pixel(t)));
    cv::line(img, {a.px0, p}, {a.px1, p}, kGrid, 1);
    cv::line(img, {a.px0 - 5, p}, {a.px0, p}, kInk, 1);
    const std::string s = tick_label(t);
    text(img, s, {a.px0 - 9 - text_width(s, 0.45), p + 5}, 0.45, kInk);
  }
  cv::rectangle(img, {a.px0, a.py1}, {a.px1, a.py0}, kInk, 1);
}

// The Pareto front of all series' points, drawn behind them as a grey staircase.
void draw_pareto_front(const PlotArea& a, const PlotMaps& m) {
  std::vector<double> all_x, all_y;
  for (const Series& s : a.chart.series) {
    for (size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i) {
      if (a.usable_x(s.x[i]) && a.usable_y(s.y[i]))
        all_x.push_back(s.x[i]), all_y.push_back(s.y[i]);
    }
  }
  const std::vector<size_t> front = pareto_indices(all_x, all_y);
  for (size_t k = 0; k < front.size(); ++k) {
    const cv::Point2d p(m.mx.to_pixel(all_x[front[k]]), m.my.to_pixel(all_y[front[k]]));
    cv::circle(a.img, p, 9, cv::Scalar(160, 160, 160), 2, cv::LINE_AA);
    if (k + 1 < front.size()) {
      const cv::Point2d q(m.mx.to_pixel(all_x[front[k + 1]]), m.my.to_pixel(all_y[front[k + 1]]));
      const cv::Point corner(static_cast<int>(q.x), static_cast<int>(p.y));  // truncated, as before
      cv::line(a.img, p, corner, cv::Scalar(190, 190, 190), 6, cv::LINE_AA);
      cv::line(a.img, corner, q, cv::Scalar(190, 190, 190), 6, cv::LINE_AA);
    }
  }
}

// The legend down the right of the plot, one entry after another.
struct Legend {
  const PlotArea& a;
  int x, y;
  void entry(const std::string& label, const cv::Scalar& c, size_t shape, bool line, bool dashed) {
    if (y > a.h - 20) return;
    if (line) {
      if (dashed)
        dashed_line(a.img, {double(x), double(y)}, {double(x + 28), double(y)}, c, 2);
      else
        cv::line(a.img, {x, y}, {x + 28, y}, c, 2, cv::LINE_AA);
    }
    if (shape != size_t(-1)) draw_marker(a.img, {x + 14, y}, shape, c);
    text(a.img, fit_text(label, 0.45, kLegendWidth - 50), {x + 36, y + 5}, 0.45, kInk);
    y += 22;
  }
};

// A series' fitted power law as a dashed line labelled with its slope; returns the label ("" when
// the fit's ends fall off the axes), warns when there are too few points.
std::string draw_power_fit(const PlotArea& a, const PlotMaps& m, const Series& s,
                           const std::vector<double>& fx, const std::vector<double>& fy,
                           const cv::Scalar& c, RenderReport& report) {
  const PowerFit fit = fit_power_law(fx, fy);
  if (!fit.ok) {
    report.warnings.push_back("series '" + s.name + "': too few points for a power-law fit");
    return "";
  }
  const auto [xmin, xmax] = std::minmax_element(fx.begin(), fx.end());
  const double ya = fit.coefficient * std::pow(*xmin, fit.slope);
  const double yb = fit.coefficient * std::pow(*xmax, fit.slope);
  if (!m.my.usable(ya) || !m.my.usable(yb)) return "";
  const cv::Point2d pa(m.mx.to_pixel(*xmin), m.my.to_pixel(ya)),
      pb(m.mx.to_pixel(*xmax), m.my.to_pixel(yb));
  dashed_line(a.img, pa, pb, cv::Scalar(60, 60, 60), 1);
  char buf[32];
  std::snprintf(buf, sizeof buf, "slope %.2f", fit.slope);
  const cv::Point at(
      static_cast<int>(std::min(pb.x - text_width(buf, 0.45), a.px1 - 4.0 - text_width(buf, 0.45))),
      static_cast<int>(std::clamp(pb.y - 8, a.py1 + 14.0, a.py0 - 4.0)));
  text(a.img, buf, at, 0.45, c, 1);
  return buf;
}

// Series si: its lines and markers inside the box, its fit, its legend entry.
void draw_series(const PlotArea& a, const PlotMaps& m, size_t si, Legend& legend,
                 RenderReport& report) {
  const Series& s = a.chart.series[si];
  const cv::Scalar c = kPalette[si % kPaletteSize];
  std::vector<cv::Point2d> pts;
  std::vector<double> fx, fy;
  for (size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i) {
    if (!(a.usable_x(s.x[i]) && a.usable_y(s.y[i]))) continue;
    const cv::Point2d p(m.mx.to_pixel(s.x[i]), m.my.to_pixel(s.y[i]));
    if (!m.in_box(p.x, p.y)) {  // outside a fixed range
      ++report.points_skipped;
      continue;
    }
    pts.push_back(p);
    fx.push_back(s.x[i]), fy.push_back(s.y[i]);
  }
  if (pts.empty()) return;
  report.points_drawn += pts.size();
  const bool lines = s.style != Style::Scatter;
  const bool marks = s.style != Style::Line;
  if (lines) {
    for (size_t k = 0; k + 1 < pts.size(); ++k) {
      if (s.dashed)
        dashed_line(a.img, pts[k], pts[k + 1], c, 2);
      else
        cv::line(a.img, pts[k], pts[k + 1], c, 2, cv::LINE_AA);
    }
  }
  if (marks) {
    for (const auto& p : pts) draw_marker(a.img, p, si, c);
  }
  std::string label = s.name;
  if (s.fit_power_law) {
    const std::string slope = draw_power_fit(a, m, s, fx, fy, c, report);
    if (!slope.empty()) label += " (" + slope + ")";
  }
  legend.entry(label, c, marks ? si : size_t(-1), lines, s.dashed);
}

void draw_markers(const PlotArea& a, const PlotMaps& m, RenderReport& report) {
  for (const Marker& mk : a.chart.markers) {
    if (!(a.usable_x(mk.x) && a.usable_y(mk.y))) continue;
    const cv::Point2d p(m.mx.to_pixel(mk.x), m.my.to_pixel(mk.y));
    if (!m.in_box(p.x, p.y)) continue;
    const cv::Point d[4] = {cv::Point(p) + cv::Point(0, -7), cv::Point(p) + cv::Point(7, 0),
                            cv::Point(p) + cv::Point(0, 7), cv::Point(p) + cv::Point(-7, 0)};
    cv::polylines(a.img, std::vector<cv::Point>(d, d + 4), true, kInk, 2, cv::LINE_AA);
    text(a.img, mk.label, cv::Point(p) + cv::Point(9, -6), 0.42, kInk);
    ++report.points_drawn;
  }
}

}  // namespace

cv::Mat render_chart(const Chart& chart, RenderReport* report_out) {
  RenderReport report;
  const int w = std::max(chart.width, kLeft + kLegendWidth + 120);
  const int h = std::max(chart.height, kTop + kBottom + 120);
  cv::Mat img(h, w, CV_8UC3, kWhite);
  const PlotArea a{img, chart, w, h, kLeft, w - kLegendWidth - 20, h - kBottom, kTop};

  std::vector<double> xs, ys;
  gather_values(a, xs, ys, report);
  draw_labels(a);
  const auto xr = axis_range(chart.x, xs);
  const auto yr = axis_range(chart.y, ys);
  if (!xr || !yr || xs.empty()) {
    text(img, "no data", {(a.px0 + a.px1) / 2 - 40, (a.py0 + a.py1) / 2}, 0.8, kInk, 2);
    report.warnings.push_back("chart '" + chart.title + "' has no drawable point");
    if (report_out) *report_out = report;
    return img;
  }
  const PlotMaps m{{xr->first, xr->second, chart.x.scale, double(a.px0), double(a.px1)},
                   {yr->first, yr->second, chart.y.scale, double(a.py0), double(a.py1)},
                   a.px0,
                   a.px1,
                   a.py0,
                   a.py1};
  draw_grid(a, m);
  if (chart.pareto_front) draw_pareto_front(a, m);
  Legend legend{a, a.px1 + 18, kTop + 12};
  for (size_t si = 0; si < chart.series.size(); ++si) draw_series(a, m, si, legend, report);
  draw_markers(a, m, report);
  if (chart.pareto_front) {
    cv::line(img, {legend.x, legend.y}, {legend.x + 28, legend.y}, cv::Scalar(190, 190, 190), 6,
             cv::LINE_AA);
    text(img, "Pareto front", {legend.x + 36, legend.y + 5}, 0.45, kInk);
  }
  if (report_out) *report_out = report;
  return img;
}

RenderReport save_chart(const Chart& chart, const std::filesystem::path& png) {
  RenderReport report;
  const cv::Mat img = render_chart(chart, &report);
  if (png.has_parent_path()) std::filesystem::create_directories(png.parent_path());
  if (!cv::imwrite(png.string(), img))
    throw std::runtime_error("cannot write chart " + png.string());
  return report;
}

}  // namespace phaco::plot
