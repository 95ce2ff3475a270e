// One file for now: the page, its tables and its inline SVG plots; issue 22 splits it by job.
#include "procedures/report/html_report.hpp"

#include "engine/core/markup.hpp"

// Two passes: read_run (report_fields.hpp) checks and copies every field the page uses into plain
// structs, then the sections below are written from those structs. A missing field is never an
// error: its section says it is left out.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <utility>
#include <vector>

#include "engine/core/error.hpp"
#include "engine/core/version.hpp"
#include "engine/plot/chart.hpp"
#include "procedures/report/report_fields.hpp"
#include "procedures/report/term_text.hpp"

namespace phaco::report {

namespace {

using nlohmann::json;
using plot::Chart;
using plot::Series;
using plot::Style;
using namespace fields;  // the report's fields, read and checked (report_fields.hpp)

// ---------------------------------------------------------------------------------------------
// Writing.

std::string escape(const std::string& s) {
  return escape_markup(s);
}

std::string note(const std::string& what) {
  return "<p class=\"note\">" + escape(what) + "</p>\n";
}

std::string png_data_uri(const cv::Mat& img) {
  std::vector<std::uint8_t> png;
  if (!cv::imencode(".png", img, png)) throw std::runtime_error("report: PNG encoding failed");
  return "data:image/png;base64," + base64_encode(png);
}

std::string figure(const std::string& id, const std::string& caption, const Chart& chart) {
  const cv::Mat img = plot::render_chart(chart);
  return "<figure id=\"plot-" + id + "\"><img alt=\"" + escape(chart.title) + "\" width=\"" +
         std::to_string(img.cols) + "\" height=\"" + std::to_string(img.rows) + "\" src=\"" +
         png_data_uri(img) + "\"><figcaption>" + escape(caption) + "</figcaption></figure>\n";
}

std::string hand_label(const Hand& h) {
  return h.tool.empty() ? h.name : h.name + " (" + h.tool + ")";
}

struct Stats {
  double mean = 0, std = 0, max = 0;
};

Stats stats(const std::vector<double>& v) {
  Stats s;
  if (v.empty()) return s;
  double sum = 0;
  s.max = v.front();
  for (double x : v) sum += x, s.max = std::max(s.max, x);
  s.mean = sum / static_cast<double>(v.size());
  double var = 0;
  for (double x : v) var += (x - s.mean) * (x - s.mean);
  s.std = std::sqrt(var / static_cast<double>(v.size()));
  return s;
}

// Chart sizes: the chart library puts the plot area 390 px narrower and 126 px shorter than the
// image (margins and legend); these make time plots wide and map plots square.
constexpr int kWideW = 1000, kWideH = 420;
constexpr int kMapW = 900, kMapH = 636;  // 510 × 510 plot area: equal scale on x and y

// "force (mN)" → "mN".
std::string unit_of(const std::string& axis_label) {
  const size_t open = axis_label.rfind('('), close = axis_label.rfind(')');
  if (open == std::string::npos || close == std::string::npos || close < open) return {};
  return axis_label.substr(open + 1, close - open - 1);
}

Chart time_chart(const std::string& title, const std::string& y_label) {
  Chart c;
  c.title = title;
  c.x.label = "time (s)";
  c.y.label = y_label;
  c.width = kWideW, c.height = kWideH;
  return c;
}

Series series(const std::string& name, Style style) {
  Series s;
  s.name = name;
  s.style = style;
  return s;
}

// Equal scale on both axes around the points' bounding box (a circle stays a circle).
void equal_axes(Chart& c, double x0, double x1, double y0, double y1) {
  const double half = std::max({(x1 - x0) / 2, (y1 - y0) / 2, 0.5}) * 1.08;
  const double cx = (x0 + x1) / 2, cy = (y0 + y1) / 2;
  c.x.min = cx - half, c.x.max = cx + half;
  c.y.min = cy - half, c.y.max = cy + half;
  c.width = kMapW, c.height = kMapH;
}

// One time series per hand (left first; an absent hand keeps its colour slot).
std::string time_figure(const Run& r, const std::string& id, const std::string& title,
                        const std::string& axis_label,
                        std::optional<std::vector<double>> Hand::*field, std::string caption,
                        std::string& notes) {
  Chart c = time_chart(title, axis_label);
  size_t drawn = 0;
  for (const Hand& h : r.hands) {
    Series s = series(hand_label(h), Style::Line);
    if (const auto& v = h.*field) {
      const size_t n = std::min(v->size(), r.t_s->size());
      if (v->size() != r.t_s->size()) {
        notes += note(title + ", " + h.name + ": " + std::to_string(v->size()) + " samples for " +
                      std::to_string(r.t_s->size()) + " times; the first " + std::to_string(n) +
                      " drawn.");
      }
      s.x.assign(r.t_s->begin(), r.t_s->begin() + static_cast<std::ptrdiff_t>(n));
      s.y.assign(v->begin(), v->begin() + static_cast<std::ptrdiff_t>(n));
      const Stats st = stats(s.y);
      // Appended piecewise: g++ 12 warns (-Wrestrict, a false positive) on `" " + string&&`.
      caption.append(" ").append(hand_label(h)).append(": mean ").append(fmt(st.mean));
      caption.append(", std ").append(fmt(st.std)).append(", max ").append(fmt(st.max));
      caption.append(" ").append(unit_of(axis_label)).append(".");
      drawn += n;
    }
    c.series.push_back(std::move(s));
  }
  if (drawn == 0) return note(title + ": left out (no samples in the report).");
  return figure(id, caption, c);
}

// Distribution as a step outline over fixed bins from 0 to the largest sample of either hand,
// in percent of each hand's samples (seed 000 Fig. 11: the histogram beside each time plot).
// With in_contact_only, zero samples (tool not touching) are left out: the distribution is that of
// the force while in contact, not dominated by the time spent away from tissue.
std::string histogram_figure(const Run& r, const std::string& id, const std::string& title,
                             const std::string& unit,
                             std::optional<std::vector<double>> Hand::*field, bool in_contact_only,
                             const std::string& caption) {
  constexpr int kBins = 24;
  double top = 0;
  size_t samples = 0;
  const auto counted = [&](double v) { return std::isfinite(v) && (!in_contact_only || v > 0); };
  for (const Hand& h : r.hands) {
    if (!(h.*field)) continue;
    for (double v : *(h.*field)) {
      if (counted(v)) top = std::max(top, v), ++samples;
    }
  }
  if (samples == 0)
    return note(title + ": left out (no " + (in_contact_only ? "samples in contact" : "samples") +
                " in the report).");
  if (!(top > 0)) top = 1;
  const double width = top / kBins;
  Chart c;
  c.title = title;
  c.x.label = unit;
  c.y.label = "% of samples";
  c.x.min = 0, c.x.max = top;
  c.y.min = 0;
  c.width = kWideW, c.height = kWideH;
  for (const Hand& h : r.hands) {
    Series s = series(hand_label(h), Style::Line);
    if (const auto& v = h.*field) {
      std::vector<double> count(kBins, 0);
      double total = 0;
      for (double x : *v) {
        if (counted(x))
          count[std::clamp(static_cast<int>(x / width), 0, kBins - 1)] += 1, total += 1;
      }
      if (total == 0) {
        c.series.push_back(std::move(s));
        continue;
      }
      s.x.push_back(0), s.y.push_back(0);
      for (int b = 0; b < kBins; ++b) {
        const double pct = 100 * count[b] / total;
        s.x.push_back(b * width), s.y.push_back(pct);
        s.x.push_back((b + 1) * width), s.y.push_back(pct);
      }
      s.x.push_back(top), s.y.push_back(0);
    }
    c.series.push_back(std::move(s));
  }
  return figure(id, caption, c);
}

// Both hands' tip paths projected on two axes of the eye frame (0 = x, 1 = y, 2 = z), with the
// samples where the tool pushed on tissue (force > 0) marked: seed 000 Fig. 11 (c).
std::string path_figure(const Run& r, const std::string& id, const std::string& title, int ax,
                        int ay, const std::string& x_label, const std::string& y_label,
                        const std::string& caption) {
  Chart c;
  c.title = title;
  c.x.label = x_label;
  c.y.label = y_label;
  double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
  std::vector<Series> contacts;
  size_t drawn = 0;
  for (const Hand& h : r.hands) {
    Series path = series(hand_label(h), Style::Line);
    Series touch = series(h.name + " in contact (force > 0)", Style::Scatter);
    if (h.pos) {
      for (size_t i = 0; i < h.pos->size(); ++i) {
        const double x = (*h.pos)[i][ax], y = (*h.pos)[i][ay];
        if (!std::isfinite(x) || !std::isfinite(y)) continue;
        path.x.push_back(x), path.y.push_back(y);
        x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
        if (h.force && i < h.force->size() && (*h.force)[i] > 0)
          touch.x.push_back(x), touch.y.push_back(y);
      }
      drawn += path.x.size();
    }
    c.series.push_back(std::move(path));
    contacts.push_back(std::move(touch));
  }
  if (drawn == 0) return note(title + ": left out (no tool positions in the report).");
  for (Series& s : contacts) c.series.push_back(std::move(s));
  equal_axes(c, x0, x1, y0, y1);
  return figure(id, caption, c);
}

Series circle(const std::string& name, double cx, double cy, double radius, bool dashed) {
  Series s = series(name, Style::Line);
  s.dashed = dashed;
  constexpr int kSegments = 48;  // few enough that each side is long enough to show dashes
  for (int k = 0; k <= kSegments; ++k) {
    const double a = 2 * M_PI * k / kSegments;
    s.x.push_back(cx + radius * std::cos(a)), s.y.push_back(cy + radius * std::sin(a));
  }
  return s;
}

std::string rhexis_figure(const Run& r, std::string& notes) {
  const Rhexis& rx = *r.rhexis;
  if (rx.outline.size() < 3)
    return note("Rhexis outline: left out (fewer than 3 outline points in the report).");
  Chart c;
  c.title = "Rhexis outline against the target circle (seen from above)";
  c.x.label = "x (mm), 3 o'clock to the right";
  c.y.label = "y (mm), 12 o'clock up";
  Series outline = series("rhexis outline", Style::Line);
  double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
  for (const auto& p : rx.outline) {
    outline.x.push_back(p[0]), outline.y.push_back(p[1]);
    x0 = std::min(x0, p[0]), x1 = std::max(x1, p[0]), y0 = std::min(y0, p[1]),
    y1 = std::max(y1, p[1]);
  }
  outline.x.push_back(rx.outline.front()[0]), outline.y.push_back(rx.outline.front()[1]);  // closed
  c.series.push_back(std::move(outline));
  const std::array<double, 2> centre = rx.target_centre.value_or(std::array<double, 2>{0, 0});
  if (rx.target_diameter) {
    for (double d : *rx.target_diameter) {
      c.series.push_back(circle("target " + fmt(d) + " mm", centre[0], centre[1], d / 2, true));
      x0 = std::min(x0, centre[0] - d / 2), x1 = std::max(x1, centre[0] + d / 2);
      y0 = std::min(y0, centre[1] - d / 2), y1 = std::max(y1, centre[1] + d / 2);
    }
  } else {
    notes += note(
        "Rhexis: the report gives no target diameter (series.rhexis.target_diameter_mm); "
        "the outline is drawn alone.");
  }
  plot::Marker m;
  m.label = "target centre";
  m.x = centre[0], m.y = centre[1];
  c.markers.push_back(m);
  equal_axes(c, x0, x1, y0, y1);
  return figure("rhexis",
                "The opening in the anterior capsule (solid) and the target band (dashed circles).",
                c);
}

std::string trench_figure(const Run& r) {
  const Trench& tr = *r.trench;
  if (tr.removed.empty()) return note("Trench: left out (no removed material in the report).");
  Chart c;
  c.title = "Trench seen from above: removed material by depth";
  c.x.label = "x (mm)";
  c.y.label = "y (mm)";
  // Five depth bands, one series each, so the legend reads as the colour scale.
  constexpr int kBands = 5;
  for (int b = 0; b < kBands; ++b) {
    c.series.push_back(series(
        "depth " + std::to_string(20 * b) + "-" + std::to_string(20 * (b + 1)) + " % of nucleus",
        Style::Scatter));
  }
  double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
  for (const auto& p : tr.removed) {
    x0 = std::min(x0, p[0]), x1 = std::max(x1, p[0]);
    y0 = std::min(y0, p[1]), y1 = std::max(y1, p[1]);
  }
  if (tr.nucleus_radius && *tr.nucleus_radius > 0) {
    const double rn = *tr.nucleus_radius;
    x0 = std::min(x0, -rn), x1 = std::max(x1, rn), y0 = std::min(y0, -rn), y1 = std::max(y1, rn);
  }
  // Seen from above, material removed at several depths over one spot overlaps; what the surgeon
  // asks of a trench is how deep it goes there, so each cell of a 60 × 60 grid over the view shows
  // its deepest removal.
  const double cell = std::max({x1 - x0, y1 - y0, 1e-3}) / 60;
  std::map<std::pair<long, long>, double> deepest;
  for (const auto& p : tr.removed) {
    const std::pair<long, long> key{std::lround(std::floor(p[0] / cell)),
                                    std::lround(std::floor(p[1] / cell))};
    const auto [it, fresh] = deepest.try_emplace(key, p[2]);
    if (!fresh) it->second = std::max(it->second, p[2]);
  }
  for (const auto& [key, depth] : deepest) {
    const int b = std::clamp(static_cast<int>(std::floor(depth * kBands)), 0, kBands - 1);
    c.series[b].x.push_back((key.first + 0.5) * cell);
    c.series[b].y.push_back((key.second + 0.5) * cell);
  }
  if (tr.nucleus_radius && *tr.nucleus_radius > 0) {
    c.series.push_back(circle("nucleus", 0, 0, *tr.nucleus_radius, false));
  }
  equal_axes(c, x0, x1, y0, y1);
  return figure("trench",
                "The deepest removal of lens material in each " + fmt(cell) +
                    " mm cell, as a fraction of the nucleus thickness, inside the nucleus circle "
                    "(from the removed tets' centroids).",
                c);
}

constexpr const char* kStyle = R"(
body { font-family: "DejaVu Sans", Helvetica, Arial, sans-serif; color: #222; margin: 24px auto;
       max-width: 1080px; padding: 0 16px; background: #fff; }
h1 { margin: 0 0 4px 0; font-size: 28px; }
h2 { border-bottom: 2px solid #ddd; padding-bottom: 4px; margin-top: 32px; font-size: 20px; }
.sub { color: #555; margin: 0; }
.scorebox { display: flex; align-items: center; gap: 28px; margin-top: 18px; }
.score { font-size: 96px; font-weight: bold; line-height: 1; padding: 18px 28px; border-radius: 12px;
         color: #fff; min-width: 160px; text-align: center; }
.score small { font-size: 28px; font-weight: normal; }
.good { background: #2e7d32; } .fair { background: #ef8f00; } .poor { background: #c62828; }
.none { background: #888; font-size: 40px; }
table { border-collapse: collapse; width: 100%; font-size: 14px; }
#metrics table, #events table { width: auto; min-width: 70%; }
th, td { text-align: left; padding: 4px 8px; border-bottom: 1px solid #e4e4e4; }
th { background: #f4f4f4; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
.met { color: #2e7d32; font-weight: bold; } .missed { color: #c62828; font-weight: bold; }
.bar { background: #e8e8e8; width: 160px; height: 12px; border-radius: 6px; }
.bar div { background: #1f77b4; height: 12px; border-radius: 6px; }
figure { margin: 16px 0; } figure img { max-width: 100%; height: auto; border: 1px solid #eee; }
figcaption { color: #555; font-size: 13px; }
.note { color: #777; font-style: italic; font-size: 13px; }
)";

std::string header_section(const Run& r) {
  std::string drill = r.drill.empty() ? "Run report" : r.drill;
  std::replace(drill.begin(), drill.end(), '_', ' ');
  if (!drill.empty())
    drill[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(drill[0])));
  std::string out = "<header>\n<h1>" + escape(drill) + "</h1>\n<p class=\"sub\">";
  out += "scenario " + escape(r.scenario.empty() ? "(not named)" : r.scenario);
  out += " · " + escape(r.date.empty() ? "date not recorded" : r.date);
  if (r.sim_time_s) out += " · " + fmt(*r.sim_time_s) + " s simulated";
  if (r.frames) out += " · " + fmt(*r.frames) + " frames";
  if (!r.state_hash.empty()) out += " · state hash " + escape(r.state_hash);
  return out + "</p>\n</header>\n";
}

std::string score_section(const Run& r) {
  std::string out = "<section id=\"score\">\n<h2>Score</h2>\n<div class=\"scorebox\">";
  if (r.score) {
    const double s = *r.score;
    const char* grade = s >= 80 ? "good" : s >= 50 ? "fair" : "poor";
    out += "<div class=\"score " + std::string(grade) + "\">" + fmt(std::round(s)) +
           "<small>/100</small></div>";
  } else {
    out += "<div class=\"score none\">no score</div>";
  }
  out += "<div>";
  for (const std::string& c : r.complications)
    out += note("FAILED: " + c + " (a complication caps the score, docs/scoring.md).");
  if (r.not_attempted) out += note("Not attempted: the step was not done, so it scores 0.");
  if (!r.score)
    out += note(
        "This report carries no metrics.score (an older report file, or a run without scoring).");
  if (!r.has_terms) {
    out += note("No per-term breakdown (score_terms) in this report.");
    return out + "</div></div>\n</section>\n";
  }
  out +=
      "<table>\n<tr><th>term "
      "(metric)</th><th>value</th><th>target</th><th>weight</th><th>points</th><th></th></tr>\n";
  double sum = 0, weights = 0;
  for (const Term& t : r.terms) {
    const double frac =
        t.weight && *t.weight > 0 && t.points ? std::clamp(*t.points / *t.weight, 0.0, 1.0) : 0;
    char width[16];
    std::snprintf(width, sizeof width, "%.0f%%", 100 * frac);
    const TermText row = term_text(t);  // as the trainer's Result panel shows it
    out += "<tr><td>" + escape(row.label) + "</td><td class=\"num\">" + escape(row.value) +
           "</td><td>" + escape(row.target) + "</td><td class=\"num\">" + row.weight +
           "</td><td class=\"num\">" + row.points +
           "</td><td><div class=\"bar\"><div style=\"width:" + width +
           "\"></div></div></td></tr>\n";
    if (t.points) sum += *t.points;
    if (t.weight) weights += *t.weight;
  }
  out += "<tr><th>total</th><td></td><td></td><td class=\"num\">" + fmt(weights) +
         "</td><td class=\"num\">" + fmt(sum) + "</td><td></td></tr>\n</table>";
  return out + "</div></div>\n</section>\n";
}

std::string metrics_section(const Run& r) {
  std::string out = "<section id=\"metrics\">\n<h2>Metrics against targets</h2>\n";
  if (!r.has_metrics || r.metrics.empty()) {
    out += note("No metrics in this report (an older report file).");
    if (!r.has_metrics) return out + "</section>\n";
  }
  if (!r.has_targets) out += note("No targets in this report: values are shown without a verdict.");
  size_t met = 0, missed = 0;
  std::string rows;
  const auto row = [&](const std::string& name, const std::string& value, const std::string& target,
                       const std::string& verdict) {
    rows += "<tr><td>" + escape(name) + "</td><td class=\"num\">" + escape(value) + "</td><td>" +
            escape(target) + "</td><td>" + verdict + "</td></tr>\n";
  };
  for (const auto& [name, value] : r.metrics) {
    const auto t = r.targets.find(name);
    if (t == r.targets.end()) {
      row(name, scalar_text(value), "—", "");
      continue;
    }
    const std::optional<double> v = as_number(value);
    if (!v) {
      row(name, scalar_text(value), band_text(t->second, metric_unit(name)), "not a number");
    } else if (within(*v, t->second)) {
      ++met;
      row(name, scalar_text(value), band_text(t->second, metric_unit(name)),
          "<span class=\"met\">met</span>");
    } else {
      ++missed;
      row(name, scalar_text(value), band_text(t->second, metric_unit(name)),
          "<span class=\"missed\">missed</span>");
    }
  }
  for (const auto& [name, band] : r.targets) {
    const bool measured = std::any_of(r.metrics.begin(), r.metrics.end(),
                                      [&](const auto& m) { return m.first == name; });
    if (!measured)
      row(name, "not measured", band_text(band, metric_unit(name)),
          "<span class=\"missed\">missed</span>"),
          ++missed;
  }
  if (r.has_targets)
    out += "<p>" + std::to_string(met) + " target(s) met, " + std::to_string(missed) +
           " missed.</p>\n";
  return out + "<table>\n<tr><th>metric</th><th>value</th><th>target</th><th></th></tr>\n" + rows +
         "</table>\n</section>\n";
}

std::string events_section(const Run& r) {
  std::string out = "<section id=\"events\">\n<h2>Events</h2>\n";
  if (!r.has_events) return out + note("No events list in this report.") + "</section>\n";
  if (r.events.empty()) return out + "<p>No events.</p>\n</section>\n";
  constexpr size_t kShown = 300;  // a long list is cut, with its length said
  out += "<table>\n<tr><th>t (s)</th><th>event</th><th>hand</th><th>details</th></tr>\n";
  for (size_t i = 0; i < std::min(kShown, r.events.size()); ++i) {
    const Event& e = r.events[i];
    std::string details;
    for (const auto& [k, v] : e.details) details += (details.empty() ? "" : ", ") + k + " " + v;
    out += "<tr><td class=\"num\">" + (e.t_s ? fmt(*e.t_s) : "—") + "</td><td>" + escape(e.kind) +
           "</td><td>" + escape(e.hand) + "</td><td>" + escape(details) + "</td></tr>\n";
  }
  out += "</table>\n";
  if (r.events.size() > kShown)
    out += note("… and " + std::to_string(r.events.size() - kShown) + " more events.");
  return out + "</section>\n";
}

std::string plots_section(const Run& r) {
  std::string out = "<section id=\"plots\">\n<h2>Hands: force, speed and paths</h2>\n";
  if (!r.has_series)
    return out + note("No series in this report (an older report file): plots left out.") +
           "</section>\n";
  if (r.hands.empty()) {
    out +=
        note("No hand series (series.hands) in this report: force, speed and path plots left out.");
  } else {
    std::string notes;
    if (!r.t_s) {
      out += note("No sample times (series.t_s): force and speed over time left out.");
    } else {
      out += time_figure(r, "force-time", "Contact force over time", "force (mN)", &Hand::force,
                         "Magnitude of the force each tool applies on tissue (seed 000 Fig. 11a).",
                         notes);
      out += histogram_figure(r, "force-histogram", "Contact force distribution (in contact)",
                              "force (mN)", &Hand::force, true,
                              "Share of each hand's in-contact samples (force > 0) per force bin.");
      out += time_figure(r, "speed-time", "Tool speed over time", "speed (mm/s)", &Hand::speed,
                         "Speed of each tool tip (seed 000 Fig. 11b).", notes);
      out += histogram_figure(r, "speed-histogram", "Tool speed distribution", "speed (mm/s)",
                              &Hand::speed, false, "Share of each hand's samples per speed bin.");
    }
    out += path_figure(
        r, "paths-top", "Tool paths seen from above (x-y)", 0, 1, "x (mm), 3 o'clock to the right",
        "y (mm), 12 o'clock up",
        "Both tips as seen through the microscope; dots where the tool touched tissue (Fig. 11c).");
    out += path_figure(r, "paths-side", "Tool paths seen from the side (x-z)", 0, 2, "x (mm)",
                       "z (mm), toward the surgeon",
                       "Both tips seen from the side: depth into the eye.");
    out += notes;
  }
  out += "</section>\n";
  out += "<section id=\"rhexis\">\n<h2>Capsulorhexis</h2>\n";
  if (r.rhexis) {
    std::string notes;
    out += rhexis_figure(r, notes) + notes;
  } else {
    out += note(
        "No rhexis outline (series.rhexis) in this report: not a capsulorhexis, or no opening was "
        "made.");
  }
  out += "</section>\n<section id=\"trench\">\n<h2>Sculpting</h2>\n";
  if (r.trench)
    out += trench_figure(r);
  else
    out += note("No trench (series.trench) in this report: not a phaco-sculpting run.");
  return out + "</section>\n";
}

}  // namespace

std::string base64_encode(std::span<const std::uint8_t> bytes) {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 3 <= bytes.size(); i += 3) {
    const std::uint32_t v =
        (std::uint32_t{bytes[i]} << 16) | (std::uint32_t{bytes[i + 1]} << 8) | bytes[i + 2];
    out += kAlphabet[v >> 18], out += kAlphabet[(v >> 12) & 63], out += kAlphabet[(v >> 6) & 63],
        out += kAlphabet[v & 63];
  }
  if (const size_t rest = bytes.size() - i; rest > 0) {
    const std::uint32_t v =
        (std::uint32_t{bytes[i]} << 16) | (rest == 2 ? std::uint32_t{bytes[i + 1]} << 8 : 0);
    out += kAlphabet[v >> 18], out += kAlphabet[(v >> 12) & 63];
    out += rest == 2 ? kAlphabet[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

std::string html_report(const json& run, const std::string& extra_sections) {
  const Run r = read_run(run);
  std::string title = "OpenPhaco report";
  if (!r.drill.empty()) title += " — " + r.drill;
  std::string page =
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>" +
      escape(title) + "</title>\n<style>" + kStyle + "</style>\n</head>\n<body>\n";
  page += header_section(r);
  page += score_section(r);
  page += metrics_section(r);
  page += events_section(r);
  page += plots_section(r);
  page += extra_sections;
  page += "<footer>" +
          note("Made by `phaco report` " + std::string(version()) + " (revision " + revision() +
               ") from the run report" +
               (r.software.empty() ? std::string(" (it does not say which build made the run)")
                                   : ", a run of " + r.software) +
               "; docs/report.md says what each part shows.") +
          "</footer>\n</body>\n</html>\n";
  return page;
}

}  // namespace phaco::report
