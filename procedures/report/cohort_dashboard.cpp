#include "procedures/report/cohort_dashboard.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>

#include "engine/core/markup.hpp"

namespace phaco::report {

namespace {

using nlohmann::json;

// A palette that stays apart for up to 10 trainees (Tableau 10), then repeats.
constexpr const char* kPalette[] = {"#4e79a7", "#f28e2b", "#e15759", "#76b7b2", "#59a14f",
                                    "#edc948", "#b07aa1", "#ff9da7", "#9c755f", "#bab0ac"};

std::string fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

std::string esc(const std::string& s) {
  return escape_markup(s);
}

// Per drill, per trainee: the scores in attempt order (unscored attempts keep their place).
using Curves = std::map<std::string, std::map<std::string, std::vector<std::optional<double>>>>;

std::string curve_chart(const std::string& drill,
                        const std::map<std::string, std::vector<std::optional<double>>>& curves,
                        const std::map<std::string, int>& colour, double pass) {
  constexpr double kW = 640, kH = 300, kL = 48, kR = 16, kT = 16, kB = 40;
  size_t attempts = 1;
  for (const auto& [t, c] : curves) attempts = std::max(attempts, c.size());
  const auto x = [&](size_t i) {
    return kL + (attempts > 1 ? double(i) / double(attempts - 1) : 0.5) * (kW - kL - kR);
  };
  const auto y = [&](double s) {
    return kT + (1.0 - std::clamp(s, 0.0, 100.0) / 100.0) * (kH - kT - kB);
  };
  std::string svg =
      "<svg class=\"curves\" viewBox=\"0 0 640 300\" width=\"640\" height=\"300\" "
      "role=\"img\" aria-label=\"learning curves, " +
      esc(drill) + "\">\n";
  for (int s = 0; s <= 100; s += 25) {
    svg += "<line x1=\"" + fmt("%.1f", kL) + "\" x2=\"" + fmt("%.1f", kW - kR) + "\" y1=\"" +
           fmt("%.1f", y(s)) + "\" y2=\"" + fmt("%.1f", y(s)) + "\" class=\"grid\"/>";
    svg += "<text x=\"" + fmt("%.1f", kL - 6) + "\" y=\"" + fmt("%.1f", y(s) + 4) +
           "\" class=\"tick\" text-anchor=\"end\">" + std::to_string(s) + "</text>\n";
  }
  for (size_t i = 0; i < attempts; ++i)
    svg += "<text x=\"" + fmt("%.1f", x(i)) + "\" y=\"" + fmt("%.1f", kH - kB + 16) +
           "\" class=\"tick\" text-anchor=\"middle\">" + std::to_string(i + 1) + "</text>";
  svg += "<text x=\"" + fmt("%.1f", (kL + kW - kR) / 2) + "\" y=\"" + fmt("%.1f", kH - 6) +
         "\" class=\"axis\" text-anchor=\"middle\">attempt</text>";
  svg += "<line class=\"pass\" x1=\"" + fmt("%.1f", kL) + "\" x2=\"" + fmt("%.1f", kW - kR) +
         "\" y1=\"" + fmt("%.1f", y(pass)) + "\" y2=\"" + fmt("%.1f", y(pass)) + "\"/>";
  svg += "<text class=\"passlabel\" x=\"" + fmt("%.1f", kW - kR - 4) + "\" y=\"" +
         fmt("%.1f", y(pass) - 4) + "\" text-anchor=\"end\">pass " + fmt("%.0f", pass) +
         "</text>\n";
  for (const auto& [trainee, scores] : curves) {
    const std::string c = kPalette[colour.at(trainee) % std::size(kPalette)];
    std::string points;
    std::string dots;
    for (size_t i = 0; i < scores.size(); ++i) {
      if (!scores[i]) continue;
      const std::string p = fmt("%.1f", x(i)) + "," + fmt("%.1f", y(*scores[i]));
      points += (points.empty() ? "" : " ") + p;
      dots += "<circle cx=\"" + fmt("%.1f", x(i)) + "\" cy=\"" + fmt("%.1f", y(*scores[i])) +
              "\" r=\"3.5\" fill=\"" + c + "\"><title>" + esc(trainee) + ", attempt " +
              std::to_string(i + 1) + ": " + fmt("%.1f", *scores[i]) + "</title></circle>";
    }
    if (points.empty()) continue;
    svg += "<polyline class=\"curve\" data-trainee=\"" + esc(trainee) + "\" data-drill=\"" +
           esc(drill) + "\" stroke=\"" + c + "\" points=\"" + points + "\"/>" + dots + "\n";
  }
  svg += "</svg>\n";
  return svg;
}

}  // namespace

std::string cohort_dashboard(std::vector<CohortAttempt> attempts, const CohortOptions& o) {
  std::stable_sort(attempts.begin(), attempts.end(),
                   [](const auto& a, const auto& b) { return a.started_utc < b.started_utc; });
  Curves curves;
  std::set<std::string> trainees;
  // Per trainee, per metric: points lost and terms seen.
  std::map<std::string, std::map<std::string, std::pair<double, int>>> lost;
  for (const CohortAttempt& a : attempts) {
    curves[a.drill][a.trainee].push_back(a.score);
    trainees.insert(a.trainee);
    if (!a.score_terms.is_array()) continue;
    for (const json& term : a.score_terms) {
      if (!term.is_object() || !term.contains("metric") || !term["metric"].is_string()) continue;
      const double w = term.value("weight", 0.0), p = term.value("points", 0.0);
      auto& [sum, n] = lost[a.trainee][a.drill + ": " + term["metric"].get<std::string>()];
      sum += std::max(0.0, w - p), ++n;
    }
  }
  std::map<std::string, int> colour;
  for (const std::string& t : trainees) colour.emplace(t, static_cast<int>(colour.size()));

  std::string h =
      "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>" + esc(o.title) +
      "</title>\n<style>body{font:14px/1.4 sans-serif;margin:24px;color:#222;max-width:1100px}"
      "h1{font-size:22px}h2{font-size:18px;margin-top:28px}table{border-collapse:collapse}"
      "td,th{border:1px solid #ccc;padding:4px 10px;text-align:left}th{background:#f2f2f2}"
      "svg .grid{stroke:#e4e4e4}svg .tick,svg .axis,svg .passlabel{font-size:11px;fill:#555}"
      "svg .pass{stroke:#2e7d32;stroke-width:1.5;stroke-dasharray:6 4}"
      "svg .curve{fill:none;stroke-width:2.5}.legend span{display:inline-block;margin-right:14px}"
      ".swatch{display:inline-block;width:12px;height:12px;margin-right:4px;vertical-align:-1px}"
      ".pass-yes{color:#2e7d32}.pass-no{color:#c62828}</style></head><body>\n";
  h += "<h1>" + esc(o.title) + "</h1>\n<p>" + std::to_string(trainees.size()) + " trainee(s), " +
       std::to_string(attempts.size()) + " finished drill(s)" +
       (o.source.empty() ? "" : " from " + esc(o.source)) +
       ". Pass line: " + fmt("%.0f", o.pass_score) + " points.</p>\n";
  if (attempts.empty()) h += "<p>No records yet.</p>\n";

  h += "<div class=\"legend\">";
  for (const auto& [t, c] : colour)
    h += "<span><i class=\"swatch\" style=\"background:" +
         std::string(kPalette[c % std::size(kPalette)]) + "\"></i>" + esc(t) + "</span>";
  h += "</div>\n";

  h += "<h2>Pass rates</h2>\n<table><tr><th>drill</th><th>trainees</th><th>latest attempt "
       "passes</th><th>attempts</th><th>attempts that pass</th></tr>\n";
  for (const auto& [drill, by_trainee] : curves) {
    int latest_pass = 0, scored_trainees = 0, all = 0, all_pass = 0;
    for (const auto& [t, scores] : by_trainee) {
      std::optional<double> last;
      for (const auto& s : scores) {
        if (!s) continue;
        ++all, all_pass += *s >= o.pass_score, last = s;
      }
      if (last) ++scored_trainees, latest_pass += *last >= o.pass_score;
    }
    const auto pct = [](int a, int b) { return b ? fmt("%.0f %%", 100.0 * a / b) : "–"; };
    h += "<tr><td>" + esc(drill) + "</td><td>" + std::to_string(by_trainee.size()) + "</td><td>" +
         std::to_string(latest_pass) + " of " + std::to_string(scored_trainees) + " (" +
         pct(latest_pass, scored_trainees) + ")</td><td>" + std::to_string(all) + "</td><td>" +
         pct(all_pass, all) + "</td></tr>\n";
  }
  h += "</table>\n";

  for (const auto& [drill, by_trainee] : curves) {
    h += "<h2>Learning curves: " + esc(drill) + "</h2>\n";
    h += curve_chart(drill, by_trainee, colour, o.pass_score);
  }

  h += "<h2>Weakest metrics</h2>\n<p>Per trainee, the score terms that lost the most points on "
       "average over their attempts.</p>\n<table><tr><th>trainee</th><th>latest scores</th>"
       "<th>weakest metrics (mean points lost of the term's weight)</th></tr>\n";
  for (const std::string& t : trainees) {
    std::string latest;
    for (const auto& [drill, by_trainee] : curves) {
      const auto it = by_trainee.find(t);
      if (it == by_trainee.end()) continue;
      std::optional<double> last;
      for (const auto& s : it->second)
        if (s) last = s;
      if (!last) continue;
      latest += (latest.empty() ? "" : ", ") + esc(drill) + " <b class=\"" +
                (*last >= o.pass_score ? "pass-yes" : "pass-no") + "\">" + fmt("%.1f", *last) +
                "</b>";
    }
    std::vector<std::pair<double, std::string>> worst;
    for (const auto& [metric, sn] : lost[t])
      if (sn.first > 0) worst.emplace_back(-sn.first / sn.second, metric);
    std::sort(worst.begin(), worst.end());
    std::string weak;
    for (size_t i = 0; i < worst.size() && i < static_cast<size_t>(o.weakest); ++i)
      weak += (weak.empty() ? "" : "; ") + esc(worst[i].second) + " (" +
              fmt("%.1f", -worst[i].first) + ")";
    h += "<tr><td>" + esc(t) + "</td><td>" + (latest.empty() ? "–" : latest) + "</td><td>" +
         (weak.empty() ? "none lost points" : weak) + "</td></tr>\n";
  }
  h += "</table>\n</body></html>\n";
  return h;
}

}  // namespace phaco::report
