#include "procedures/report/compare_section.hpp"

#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <vector>

#include "engine/core/markup.hpp"
#include "engine/plot/chart.hpp"
#include "procedures/report/html_report.hpp"

namespace phaco::report {

namespace {

std::string fmt(double v, const char* f = "%.3g") {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

std::string cell(const std::string& s) {
  return "<td>" + escape_markup(s) + "</td>";
}

// One figure, two panels sharing the run's time axis: the aligned path distance (mm) above, the
// force difference (mN) below; stacked, since millimetres would vanish on a scale of tens of mN.
std::string plot(const compare::Comparison& c) {
  auto panel = [&](const std::string& title, const std::string& y_label,
                   std::vector<double> compare::HandComparison::*field) {
    plot::Chart chart;
    chart.title = title;
    chart.x.label = "run time (s)";
    chart.y.label = y_label;
    chart.width = 1000, chart.height = 360;
    for (const compare::HandComparison& h : c.hands) {
      plot::Series s;
      s.name = h.hand;
      s.style = plot::Style::Line;
      s.x = h.t_s, s.y = h.*field;
      chart.series.push_back(std::move(s));
    }
    return plot::render_chart(chart);
  };
  cv::Mat img;
  cv::vconcat(panel("Path distance to the expert after DTW alignment", "distance (mm)",
                    &compare::HandComparison::distance_mm),
              panel("Contact force, run - expert, after alignment", "force diff (mN)",
                    &compare::HandComparison::force_diff_mN_series),
              img);
  const std::string alt = "Compared with the expert: path distance and force difference";
  std::vector<std::uint8_t> png;
  if (!cv::imencode(".png", img, png)) throw std::runtime_error("report: PNG encoding failed");
  return "<figure id=\"plot-compare\"><img alt=\"" + escape_markup(alt) + "\" width=\"" +
         std::to_string(img.cols) + "\" height=\"" + std::to_string(img.rows) +
         "\" src=\"data:image/png;base64," + base64_encode(png) +
         "\"><figcaption>Per hand: the distance between the run's tool tip and the expert's "
         "matched tip, and the contact force difference (run − expert), on the run's time axis."
         "</figcaption></figure>\n";
}

}  // namespace

std::string compare_section(const compare::Comparison& c) {
  std::string out = "<section id=\"compare\">\n<h2>Compared with the expert</h2>\n";
  out += "<p>Expert: " + escape_markup(c.expert_file) + ". Time: run " + fmt(c.run_time_s) +
         " s, expert " + fmt(c.expert_time_s) + " s, ratio " + fmt(c.time_ratio) +
         ". The tool-tip paths are aligned by dynamic time warping (Sakoe &amp; Chiba band) "
         "before the differences are taken; the rows \"equal time\" compare at equal times "
         "without alignment.</p>\n";
  out +=
      "<table>\n<tr><th>hand</th><th>alignment</th><th>path distance mean / max (mm)</th>"
      "<th>speed run−expert mean / rms (mm/s)</th><th>force run−expert mean / rms (mN)</th></tr>\n";
  for (const compare::HandComparison& h : c.hands) {
    auto row = [&](const char* how, const compare::DifferenceStats& d,
                   const compare::DifferenceStats& v, const compare::DifferenceStats& f) {
      out += "<tr>" + cell(h.hand) + cell(how) + cell(fmt(d.mean) + " / " + fmt(d.max)) +
             cell(fmt(v.mean) + " / " + fmt(v.rms)) + cell(fmt(f.mean) + " / " + fmt(f.rms)) +
             "</tr>\n";
    };
    row("DTW", h.path_distance_mm, h.speed_diff_mm_s, h.force_diff_mN);
    row("equal time", h.plain_path_distance_mm, h.plain_speed_diff_mm_s, h.plain_force_diff_mN);
  }
  out += "</table>\n";
  out += plot(c);
  if (!c.metrics.empty()) {
    out += "<table>\n<tr><th>metric</th><th>run</th><th>expert</th><th>run − expert</th></tr>\n";
    for (const compare::MetricDifference& m : c.metrics) {
      out += "<tr>" + cell(m.name) + cell(fmt(m.run, "%.4g")) + cell(fmt(m.expert, "%.4g")) +
             cell(fmt(m.difference, "%+.4g")) + "</tr>\n";
    }
    out += "</table>\n";
  }
  out += "</section>\n";
  return out;
}

}  // namespace phaco::report
