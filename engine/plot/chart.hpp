#pragma once
// A small chart library on OpenCV (issue 22: a library of the engine, used by the perf harness
// and by the trainee's run report alike): line and scatter series on linear or
// log10 axes (decade ticks), axis labels with units, title, legend, a fitted power-law slope drawn
// and annotated ("slope 1.02"), reference markers (published figures), and the Pareto front of a
// speed-versus-accuracy chart (lower-left is better on both axes).
//
// Bad input never crashes: a NaN or infinite point, or a non-positive value on a log axis, is
// skipped and counted; an empty series is left out of the legend and reported; a chart with no
// drawable point still renders its frame and says "no data".
//
// OpenCV's Hershey fonts are ASCII only: write "us", not "µs".
#include <cstddef>
#include <filesystem>
#include <opencv2/core.hpp>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace phaco::plot {

enum class Scale { Linear, Log10 };

struct Axis {
  std::string label;  // with its unit, e.g. "vertices" or "ns per vertex per step"
  Scale scale = Scale::Linear;
  std::optional<double> min, max;  // fixed range; otherwise from the data (log: whole decades)
};

enum class Style { Line, Scatter, LineAndMarkers };

struct Series {
  std::string name;
  std::vector<double> x, y;
  Style style = Style::LineAndMarkers;
  bool fit_power_law = false;  // draw y = c·x^s through the points, legend shows "slope s"
  bool dashed = false;
};

// A labelled point drawn as a hollow diamond: e.g. a figure a seed paper published.
struct Marker {
  std::string label;
  double x = 0, y = 0;
};

struct Chart {
  std::string title;
  Axis x, y;
  std::vector<Series> series;
  std::vector<Marker> markers;
  bool pareto_front =
      false;  // join the points no other point beats on both x and y (both minimised)
  int width = 960, height = 640;
};

struct PowerFit {
  bool ok = false;         // at least two usable points with distinct x
  double slope = 0;        // s in y = c·x^s
  double coefficient = 0;  // c
  double r2 = 0;           // on log-log
  size_t points = 0;       // usable points (finite, positive)
};

// Least squares on (log x, log y); skips non-finite and non-positive points.
PowerFit fit_power_law(std::span<const double> x, std::span<const double> y);

// Maps data values to pixels along one axis: [lo, hi] → [p0, p1] (p1 < p0 for a y axis).
struct AxisMap {
  double lo = 0, hi = 1;
  Scale scale = Scale::Linear;
  double p0 = 0, p1 = 1;

  bool usable(double v) const;      // finite, and > 0 on a log axis
  double to_pixel(double v) const;  // callers check usable() first
};

// Data range of an axis from the values (ignoring unusable ones) and the axis's fixed bounds: a log
// axis is widened to whole decades, a linear one to "nice" 1-2-5 steps. Returns nullopt when no
// value is usable and no bounds are fixed.
std::optional<std::pair<double, double>> axis_range(const Axis& axis,
                                                    std::span<const double> values);

// Tick positions inside [lo, hi]: every decade on a log axis (with 2 and 5 when it spans under two
// decades), 1-2-5 steps on a linear one.
std::vector<double> axis_ticks(double lo, double hi, Scale scale);

// Indices (into the flattened list of all series' points, series by series) of the Pareto front,
// sorted by x.
std::vector<size_t> pareto_indices(std::span<const double> x, std::span<const double> y);

struct RenderReport {
  size_t points_drawn = 0;
  size_t points_skipped = 0;
  std::vector<std::string> warnings;  // one line per skipped series or point group
};

// Renders to an 8-bit BGR image of chart.width × chart.height.
cv::Mat render_chart(const Chart& chart, RenderReport* report = nullptr);

// render_chart then cv::imwrite; throws std::runtime_error naming the file if it cannot be written.
RenderReport save_chart(const Chart& chart, const std::filesystem::path& png);

}  // namespace phaco::plot
