// engine/plot/chart: renders real pixels, maps log axes by decades, fits power laws exactly, and
// survives bad input (NaN, empty series, non-positive values on a log axis) by skipping and
// reporting.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <opencv2/imgcodecs.hpp>

#include "engine/plot/chart.hpp"

namespace phaco::plot {
namespace {

// Pixels that are neither white nor grey-ish text: coloured series ink.
int coloured_pixels(const cv::Mat& img) {
  int n = 0;
  for (int r = 0; r < img.rows; ++r) {
    for (int c = 0; c < img.cols; ++c) {
      const cv::Vec3b p = img.at<cv::Vec3b>(r, c);
      const int mx = std::max({p[0], p[1], p[2]}), mn = std::min({p[0], p[1], p[2]});
      if (mx - mn > 60) ++n;
    }
  }
  return n;
}

Chart two_series() {
  Chart c;
  c.title = "test";
  c.x = {"vertices", Scale::Log10};
  c.y = {"time (us)", Scale::Log10};
  c.series.push_back({"a", {1e3, 1e4, 1e5}, {1, 10, 100}});
  c.series.push_back({"b", {1e3, 1e4, 1e5}, {3, 20, 400}, Style::Scatter});
  return c;
}

TEST(Chart, RendersNonTrivialPixels) {
  RenderReport report;
  const cv::Mat img = render_chart(two_series(), &report);
  ASSERT_EQ(img.type(), CV_8UC3);
  EXPECT_EQ(img.cols, 960);
  EXPECT_EQ(img.rows, 640);
  EXPECT_EQ(report.points_drawn, 6u);
  EXPECT_EQ(report.points_skipped, 0u);
  EXPECT_GT(coloured_pixels(img), 500);  // lines and markers in colour
  // Some dark ink (axes, labels) too.
  cv::Mat grey;
  cv::extractChannel(img, grey, 0);
  EXPECT_GT(cv::countNonZero(grey < 100), 500);
}

TEST(Chart, EmptyChartRendersFrameWithoutData) {
  Chart c;
  c.title = "nothing";
  RenderReport report;
  const cv::Mat img = render_chart(c, &report);
  EXPECT_EQ(report.points_drawn, 0u);
  EXPECT_FALSE(report.warnings.empty());
  EXPECT_EQ(coloured_pixels(img), 0);
}

TEST(Chart, LogAxisMapsDecadesEvenly) {
  const AxisMap m{1.0, 1000.0, Scale::Log10, 0.0, 300.0};
  EXPECT_DOUBLE_EQ(m.to_pixel(1.0), 0.0);
  EXPECT_NEAR(m.to_pixel(10.0), 100.0, 1e-9);
  EXPECT_NEAR(m.to_pixel(100.0), 200.0, 1e-9);
  EXPECT_NEAR(m.to_pixel(1000.0), 300.0, 1e-9);
  EXPECT_NEAR(m.to_pixel(std::sqrt(10.0)), 50.0, 1e-9);
  EXPECT_FALSE(m.usable(0.0));
  EXPECT_FALSE(m.usable(-1.0));
  // A y axis runs upward: larger values map to smaller rows.
  const AxisMap y{0.01, 100.0, Scale::Log10, 400.0, 0.0};
  EXPECT_NEAR(y.to_pixel(1.0), 200.0, 1e-9);
}

TEST(Chart, LogRangeWidensToWholeDecadesAndTicksAreDecades) {
  const Axis axis{"x", Scale::Log10};
  const double values[] = {2.5, 40.0, 7000.0};
  const auto range = axis_range(axis, values);
  ASSERT_TRUE(range);
  EXPECT_DOUBLE_EQ(range->first, 1.0);
  EXPECT_DOUBLE_EQ(range->second, 10000.0);
  const std::vector<double> ticks = axis_ticks(range->first, range->second, Scale::Log10);
  ASSERT_EQ(ticks.size(), 5u);
  for (size_t i = 0; i < ticks.size(); ++i)
    EXPECT_NEAR(ticks[i], std::pow(10.0, double(i)), 1e-9 * ticks[i]);
  // Under two decades, 2 and 5 are ticked too.
  const std::vector<double> minor = axis_ticks(1.0, 10.0, Scale::Log10);
  EXPECT_EQ(minor, (std::vector<double>{1.0, 2.0, 5.0, 10.0}));
}

TEST(Chart, LinearTicksAreNiceSteps) {
  const std::vector<double> ticks = axis_ticks(0.0, 2.5, Scale::Linear);
  ASSERT_GE(ticks.size(), 3u);
  const double step = ticks[1] - ticks[0];
  EXPECT_TRUE(std::fabs(step - 0.5) < 1e-12 || std::fabs(step - 0.2) < 1e-12 ||
              std::fabs(step - 1.0) < 1e-12);
  EXPECT_DOUBLE_EQ(ticks.front(), 0.0);
}

TEST(Chart, PowerLawFitOfExactDataIsExact) {
  std::vector<double> x, y;
  for (double v : {1e3, 2e3, 8e3, 1.28e5}) x.push_back(v), y.push_back(3.5 * std::pow(v, 1.02));
  const PowerFit fit = fit_power_law(x, y);
  ASSERT_TRUE(fit.ok);
  EXPECT_NEAR(fit.slope, 1.02, 1e-12);
  EXPECT_NEAR(fit.coefficient, 3.5, 1e-9);
  EXPECT_NEAR(fit.r2, 1.0, 1e-12);
  EXPECT_EQ(fit.points, 4u);
}

TEST(Chart, PowerLawFitSkipsUnusablePointsAndNeedsTwo) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<double> x = {10, 100, -5, nan, 1000},
                            y = {2, 4, 3, 1, 8};  // slope log10(2) on usable points
  const PowerFit fit = fit_power_law(x, y);
  ASSERT_TRUE(fit.ok);
  EXPECT_EQ(fit.points, 3u);
  EXPECT_NEAR(fit.slope, std::log10(2.0), 1e-12);
  EXPECT_FALSE(fit_power_law(std::vector<double>{5}, std::vector<double>{1}).ok);
  EXPECT_FALSE(
      fit_power_law(std::vector<double>{5, 5}, std::vector<double>{1, 2}).ok);  // no x spread
  EXPECT_FALSE(fit_power_law(std::vector<double>{}, std::vector<double>{}).ok);
}

TEST(Chart, BadInputIsSkippedAndReportedNeverCrashes) {
  const double nan = std::numeric_limits<double>::quiet_NaN(),
               inf = std::numeric_limits<double>::infinity();
  Chart c = two_series();
  c.series.push_back({"bad", {nan, 1e4, -1, 0, inf}, {1, nan, 5, 5, 5}});
  c.series.push_back({"empty"});
  c.series.push_back({"ragged", {1e3, 1e4, 1e5}, {2}});
  c.series[0].fit_power_law = true;
  c.series.push_back({"one point fit", {1e4}, {5}, Style::LineAndMarkers, true});
  c.markers.push_back({"negative", -1, 5});
  c.pareto_front = true;
  RenderReport report;
  cv::Mat img;
  ASSERT_NO_THROW(img = render_chart(c, &report));
  EXPECT_EQ(report.points_skipped, 5u);        // every point of "bad"
  EXPECT_EQ(report.points_drawn, 6u + 1 + 1);  // two_series, ragged's first, the one-point series
  EXPECT_GE(report.warnings.size(), 5u);       // bad, empty, ragged, one-point fit, marker
  EXPECT_FALSE(img.empty());

  // All-NaN chart on log axes: frame only, reported.
  Chart all_bad;
  all_bad.x.scale = all_bad.y.scale = Scale::Log10;
  all_bad.series.push_back({"nan", {nan, 0}, {1, -1}});
  RenderReport r2;
  ASSERT_NO_THROW(render_chart(all_bad, &r2));
  EXPECT_EQ(r2.points_drawn, 0u);
  EXPECT_EQ(r2.points_skipped, 2u);
}

TEST(Chart, FixedRangeClipsOutsidePoints) {
  Chart c;
  c.x = {"x", Scale::Linear, 0.0, 10.0};
  c.y = {"y", Scale::Linear, 0.0, 10.0};
  c.series.push_back({"s", {1, 5, 20}, {1, 5, 5}});
  RenderReport report;
  render_chart(c, &report);
  EXPECT_EQ(report.points_drawn, 2u);
  EXPECT_EQ(report.points_skipped, 1u);
}

TEST(Chart, ParetoFrontKeepsUndominatedPoints) {
  // (cost, error): (1, 10) (2, 5) (3, 7) (4, 1) (5, 1): front is the 1st, 2nd and 4th.
  const std::vector<double> x = {3, 1, 4, 2, 5}, y = {7, 10, 1, 5, 1};
  EXPECT_EQ(pareto_indices(x, y), (std::vector<size_t>{1, 3, 2}));
}

TEST(Chart, SavesPng) {
  const auto file = std::filesystem::temp_directory_path() / "phaco_test_chart.png";
  std::filesystem::remove(file);
  save_chart(two_series(), file);
  const cv::Mat back = cv::imread(file.string());
  EXPECT_EQ(back.cols, 960);
  EXPECT_EQ(back.rows, 640);
  std::filesystem::remove(file);
  EXPECT_THROW(save_chart(two_series(), "/proc/no/such/dir/x.png"), std::exception);
}

}  // namespace
}  // namespace phaco::plot
