#include "procedures/compare/compare.hpp"

// Two passes, as the HTML report does: read() checks every field the comparison uses and copies
// it into plain vectors (a wrong type is reported with its JSON path before anything is
// computed), then the hands are aligned and compared.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <stdexcept>

#include "engine/core/error.hpp"

namespace phaco::compare {

namespace {

using nlohmann::json;

struct HandSeries {
  std::vector<double> pos;  // x, y, z per sample, mm
  std::vector<double> speed, force;
};

struct Parsed {
  std::string drill;
  std::vector<double> t;
  std::map<std::string, HandSeries> hands;  // "left" < "right": left first
  std::vector<std::pair<std::string, double>> metrics;
};

[[noreturn]] void bad(const std::string& file, const std::string& field, const std::string& what) {
  throw InputError(file + ": " + field + ": " + what);
}

const json& member(const json& j, const std::string& key, const std::string& file,
                   const std::string& path) {
  const auto it = j.find(key);
  if (it == j.end()) bad(file, path.empty() ? key : path + "." + key, "missing");
  return *it;
}

std::vector<double> numbers(const json& j, const std::string& file, const std::string& path) {
  if (!j.is_array()) bad(file, path, "expected an array of numbers");
  std::vector<double> v;
  v.reserve(j.size());
  for (size_t k = 0; k < j.size(); ++k) {
    if (!j[k].is_number()) bad(file, path + "[" + std::to_string(k) + "]", "expected a number");
    v.push_back(j[k].get<double>());
  }
  return v;
}

Parsed read(const json& r, const std::string& file) {
  if (!r.is_object()) bad(file, "(top level)", "expected a run report object");
  Parsed p;
  const json& drill = member(r, "drill", file, "");
  if (!drill.is_string()) bad(file, "drill", "expected a string");
  p.drill = drill.get<std::string>();

  const json& series = member(r, "series", file, "");
  if (!series.is_object()) bad(file, "series", "expected an object");
  p.t = numbers(member(series, "t_s", file, "series"), file, "series.t_s");
  if (p.t.empty()) bad(file, "series.t_s", "no samples");
  for (size_t k = 1; k < p.t.size(); ++k) {
    if (!(p.t[k] >= p.t[k - 1])) {
      bad(file, "series.t_s[" + std::to_string(k) + "]", "times must not decrease");
    }
  }
  const json& hands = member(series, "hands", file, "series");
  if (!hands.is_object()) bad(file, "series.hands", "expected an object");
  if (hands.empty()) bad(file, "series.hands", "no hand");
  for (const auto& [name, h] : hands.items()) {
    const std::string path = "series.hands." + name;
    if (!h.is_object()) bad(file, path, "expected an object");
    HandSeries s;
    const json& pos = member(h, "pos_mm", file, path);
    if (!pos.is_array()) bad(file, path + ".pos_mm", "expected an array of [x, y, z]");
    s.pos.reserve(3 * pos.size());
    for (size_t k = 0; k < pos.size(); ++k) {
      const std::string at = path + ".pos_mm[" + std::to_string(k) + "]";
      const std::vector<double> xyz = numbers(pos[k], file, at);
      if (xyz.size() != 3) bad(file, at, "expected [x, y, z] in mm");
      s.pos.insert(s.pos.end(), xyz.begin(), xyz.end());
    }
    s.speed = numbers(member(h, "speed_mm_s", file, path), file, path + ".speed_mm_s");
    s.force = numbers(member(h, "force_mN", file, path), file, path + ".force_mN");
    const size_t n = p.t.size();
    auto same_length = [&](size_t size, const char* field) {
      if (size != n) {
        bad(file, path + "." + field,
            std::to_string(size) + " samples for " + std::to_string(n) + " times in series.t_s");
      }
    };
    same_length(pos.size(), "pos_mm");
    same_length(s.speed.size(), "speed_mm_s");
    same_length(s.force.size(), "force_mN");
    p.hands.emplace(name, std::move(s));
  }

  const json& metrics = member(r, "metrics", file, "");
  if (!metrics.is_object()) bad(file, "metrics", "expected an object");
  for (const auto& [name, v] : metrics.items()) {
    if (v.is_null()) continue;  // not measured in this run
    if (v.is_boolean()) {
      p.metrics.emplace_back(name, v.get<bool>() ? 1.0 : 0.0);
    } else if (v.is_number()) {
      p.metrics.emplace_back(name, v.get<double>());
    } else {
      bad(file, "metrics." + name, "expected a number");
    }
  }
  return p;
}

void accumulate(DifferenceStats& s, const std::vector<double>& v) {
  if (v.empty()) return;
  double sum = 0, sq = 0, max = 0;
  for (double x : v) sum += x, sq += x * x, max = std::max(max, std::abs(x));
  const auto n = static_cast<double>(v.size());
  s.mean = sum / n;
  s.rms = std::sqrt(sq / n);
  s.max = max;
}

double distance(const std::vector<double>& a, size_t i, const std::vector<double>& b, size_t j) {
  const double dx = a[3 * i] - b[3 * j], dy = a[3 * i + 1] - b[3 * j + 1],
               dz = a[3 * i + 2] - b[3 * j + 2];
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

// The expert's sample interval holding time t: index k and weight f, value = (1−f)·v[k] + f·v[k+1].
std::pair<size_t, double> at_time(const std::vector<double>& t, double time) {
  if (time <= t.front() || t.size() == 1) return {0, 0.0};
  if (time >= t.back()) return {t.size() - 1, 0.0};
  const size_t k = static_cast<size_t>(std::upper_bound(t.begin(), t.end(), time) - t.begin()) - 1;
  const double span = t[k + 1] - t[k];
  return {k, span > 0 ? (time - t[k]) / span : 0.0};
}

HandComparison compare_hand(const std::string& name, const Parsed& run, const HandSeries& a,
                            const Parsed& expert, const HandSeries& b,
                            const CompareOptions& options) {
  HandComparison h;
  h.hand = name;
  const size_t n = run.t.size(), m = expert.t.size();
  h.run_samples = n, h.expert_samples = m;
  // Sakoe–Chiba window: r·max(n, m), and at least the slope of the scaled diagonal plus one so
  // consecutive rows' windows touch (every cell in the window is reachable).
  const double slope = (n > 1 && m > 1) ? static_cast<double>(m - 1) / static_cast<double>(n - 1)
                                        : static_cast<double>(std::max(n, m));
  h.band = std::max(
      static_cast<size_t>(std::ceil(options.band_fraction * static_cast<double>(std::max(n, m)))),
      static_cast<size_t>(std::ceil(slope)) + 1);
  const auto path = dtw_path(a.pos, b.pos, h.band);

  std::vector<double> sum_d(n, 0), sum_v(n, 0), sum_f(n, 0), sum_t(n, 0);
  std::vector<int> count(n, 0);
  for (const auto& [i, j] : path) {
    sum_d[i] += distance(a.pos, i, b.pos, j);
    sum_v[i] += a.speed[i] - b.speed[j];
    sum_f[i] += a.force[i] - b.force[j];
    sum_t[i] += expert.t[j];
    ++count[i];
  }
  h.t_s = run.t;
  h.expert_t_s.resize(n), h.distance_mm.resize(n), h.speed_diff_mm_s_series.resize(n),
      h.force_diff_mN_series.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const double c = count[i];  // ≥ 1: the warping path visits every row
    h.expert_t_s[i] = sum_t[i] / c;
    h.distance_mm[i] = sum_d[i] / c;
    h.speed_diff_mm_s_series[i] = sum_v[i] / c;
    h.force_diff_mN_series[i] = sum_f[i] / c;
  }
  accumulate(h.path_distance_mm, h.distance_mm);
  accumulate(h.speed_diff_mm_s, h.speed_diff_mm_s_series);
  accumulate(h.force_diff_mN, h.force_diff_mN_series);

  // Without warping: the expert at the run's times.
  std::vector<double> d(n), v(n), f(n);
  for (size_t i = 0; i < n; ++i) {
    const auto [k, w] = at_time(expert.t, run.t[i]);
    const size_t k1 = std::min(k + 1, m - 1);
    double sq = 0;
    for (int c = 0; c < 3; ++c) {
      const double e = (1 - w) * b.pos[3 * k + c] + w * b.pos[3 * k1 + c];
      sq += (a.pos[3 * i + c] - e) * (a.pos[3 * i + c] - e);
    }
    d[i] = std::sqrt(sq);
    v[i] = a.speed[i] - ((1 - w) * b.speed[k] + w * b.speed[k1]);
    f[i] = a.force[i] - ((1 - w) * b.force[k] + w * b.force[k1]);
  }
  accumulate(h.plain_path_distance_mm, d);
  accumulate(h.plain_speed_diff_mm_s, v);
  accumulate(h.plain_force_diff_mN, f);
  return h;
}

json stats_json(const DifferenceStats& s) {
  return {{"mean", s.mean}, {"rms", s.rms}, {"max", s.max}};
}

}  // namespace

std::vector<std::pair<size_t, size_t>> dtw_path(const std::vector<double>& a,
                                                const std::vector<double>& b, size_t band) {
  const size_t n = a.size() / 3, m = b.size() / 3;
  if (n == 0 || m == 0) throw std::invalid_argument("dtw_path: an empty path");
  const double slope = n > 1 ? static_cast<double>(m - 1) / static_cast<double>(n - 1) : 0.0;
  const double w = n > 1 ? static_cast<double>(band) : static_cast<double>(m);
  std::vector<size_t> lo(n), hi(n);
  for (size_t i = 0; i < n; ++i) {
    const double c = slope * static_cast<double>(i);
    lo[i] = static_cast<size_t>(std::max(0.0, std::ceil(c - w - 1e-9)));
    hi[i] = static_cast<size_t>(std::min(static_cast<double>(m - 1), std::floor(c + w + 1e-9)));
  }
  lo[0] = 0, hi[n - 1] = m - 1;
  size_t width = 0;
  for (size_t i = 0; i < n; ++i) width = std::max(width, hi[i] - lo[i] + 1);
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::vector<double> D(n * width, kInf);  // row i holds columns lo[i]..hi[i]
  auto at = [&](size_t i, size_t j) {
    return (j < lo[i] || j > hi[i]) ? kInf : D[i * width + (j - lo[i])];
  };
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = lo[i]; j <= hi[i]; ++j) {
      double best = 0;
      if (i > 0 || j > 0) {
        best = kInf;
        if (i > 0) best = std::min(best, at(i - 1, j));
        if (j > 0) best = std::min(best, at(i, j - 1));
        if (i > 0 && j > 0) best = std::min(best, at(i - 1, j - 1));
      }
      D[i * width + (j - lo[i])] = distance(a, i, b, j) + best;
    }
  }
  // Back from the end; ties go to the diagonal (the shortest warping path).
  std::vector<std::pair<size_t, size_t>> path;
  path.reserve(n + m);
  size_t i = n - 1, j = m - 1;
  path.emplace_back(i, j);
  while (i > 0 || j > 0) {
    const double diag = (i > 0 && j > 0) ? at(i - 1, j - 1) : kInf;
    const double up = i > 0 ? at(i - 1, j) : kInf;
    const double left = j > 0 ? at(i, j - 1) : kInf;
    if (diag <= up && diag <= left) {
      --i, --j;
    } else if (up <= left) {
      --i;
    } else {
      --j;
    }
    path.emplace_back(i, j);
  }
  std::reverse(path.begin(), path.end());
  return path;
}

Comparison compare_reports(const json& run, const json& expert, const std::string& run_name,
                           const std::string& expert_name, const CompareOptions& options) {
  const Parsed a = read(run, run_name), b = read(expert, expert_name);
  if (a.drill != b.drill) {
    throw InputError(run_name + ": drill: '" + a.drill + "' is not the expert's drill '" + b.drill +
                     "' (" + expert_name + ")");
  }
  for (const auto& [name, s] : a.hands) {
    if (!b.hands.contains(name))
      bad(expert_name, "series.hands." + name, "missing (the run has it)");
  }
  for (const auto& [name, s] : b.hands) {
    if (!a.hands.contains(name))
      bad(run_name, "series.hands." + name, "missing (the expert has it)");
  }
  Comparison c;
  c.run_file = run_name, c.expert_file = expert_name, c.drill = a.drill;
  c.run_time_s = a.t.back(), c.expert_time_s = b.t.back();
  c.time_ratio = c.expert_time_s > 0 ? c.run_time_s / c.expert_time_s : 0.0;
  for (const auto& [name, s] : a.hands) {
    c.hands.push_back(compare_hand(name, a, s, b, b.hands.at(name), options));
  }
  std::map<std::string, double> theirs(b.metrics.begin(), b.metrics.end());
  std::map<std::string, double> ours(a.metrics.begin(), a.metrics.end());
  for (const auto& [name, value] : ours) {
    const auto it = theirs.find(name);
    if (it == theirs.end()) continue;
    c.metrics.push_back({name, value, it->second, value - it->second});
  }
  return c;
}

json read_report(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file.string() + ": cannot open the run report");
  try {
    return json::parse(in);
  } catch (const json::parse_error& e) {
    throw InputError(file.string() + ": not valid JSON (" + e.what() + ")");
  }
}

Comparison compare_files(const std::filesystem::path& run, const std::filesystem::path& expert,
                         const CompareOptions& options) {
  return compare_reports(read_report(run), read_report(expert), run.string(), expert.string(),
                         options);
}

json to_json(const Comparison& c) {
  json hands = json::object();
  for (const HandComparison& h : c.hands) {
    hands[h.hand] = {{"samples", {{"run", h.run_samples}, {"expert", h.expert_samples}}},
                     {"band_samples", h.band},
                     {"aligned",
                      {{"path_distance_mm", stats_json(h.path_distance_mm)},
                       {"speed_diff_mm_s", stats_json(h.speed_diff_mm_s)},
                       {"force_diff_mN", stats_json(h.force_diff_mN)}}},
                     {"plain",
                      {{"path_distance_mm", stats_json(h.plain_path_distance_mm)},
                       {"speed_diff_mm_s", stats_json(h.plain_speed_diff_mm_s)},
                       {"force_diff_mN", stats_json(h.plain_force_diff_mN)}}},
                     {"series",
                      {{"t_s", h.t_s},
                       {"expert_t_s", h.expert_t_s},
                       {"path_distance_mm", h.distance_mm},
                       {"speed_diff_mm_s", h.speed_diff_mm_s_series},
                       {"force_diff_mN", h.force_diff_mN_series}}}};
  }
  json metrics = json::object();
  for (const MetricDifference& m : c.metrics) {
    metrics[m.name] = {{"run", m.run}, {"expert", m.expert}, {"difference", m.difference}};
  }
  return {
      {"run", c.run_file},
      {"expert", c.expert_file},
      {"drill", c.drill},
      {"alignment", "dtw, Sakoe-Chiba band, on the tool-tip paths"},
      {"time", {{"run_s", c.run_time_s}, {"expert_s", c.expert_time_s}, {"ratio", c.time_ratio}}},
      {"hands", hands},
      {"metrics", metrics}};
}

std::string summary_text(const Comparison& c) {
  std::string out;
  char buf[512];
  std::snprintf(buf, sizeof buf, "%s compared with the expert %s (%s)\n", c.run_file.c_str(),
                c.expert_file.c_str(), c.drill.c_str());
  out += buf;
  std::snprintf(buf, sizeof buf, "time: run %.2f s, expert %.2f s, ratio %.3f\n", c.run_time_s,
                c.expert_time_s, c.time_ratio);
  out += buf;
  std::snprintf(buf, sizeof buf, "%-6s %-11s %21s %23s %23s\n", "hand", "alignment",
                "path dist mean/max mm", "speed diff mean/rms mm/s", "force diff mean/rms mN");
  out += buf;
  for (const HandComparison& h : c.hands) {
    std::snprintf(buf, sizeof buf, "%-6s %-11s %10.3f %10.3f %11.3f %11.3f %11.3f %11.3f\n",
                  h.hand.c_str(), "dtw", h.path_distance_mm.mean, h.path_distance_mm.max,
                  h.speed_diff_mm_s.mean, h.speed_diff_mm_s.rms, h.force_diff_mN.mean,
                  h.force_diff_mN.rms);
    out += buf;
    std::snprintf(buf, sizeof buf, "%-6s %-11s %10.3f %10.3f %11.3f %11.3f %11.3f %11.3f\n", "",
                  "equal time", h.plain_path_distance_mm.mean, h.plain_path_distance_mm.max,
                  h.plain_speed_diff_mm_s.mean, h.plain_speed_diff_mm_s.rms,
                  h.plain_force_diff_mN.mean, h.plain_force_diff_mN.rms);
    out += buf;
  }
  if (!c.metrics.empty()) {
    std::snprintf(buf, sizeof buf, "%-34s %12s %12s %12s\n", "metric", "run", "expert",
                  "run-expert");
    out += buf;
  }
  for (const MetricDifference& m : c.metrics) {
    std::snprintf(buf, sizeof buf, "%-34s %12.4g %12.4g %+12.4g\n", m.name.c_str(), m.run, m.expert,
                  m.difference);
    out += buf;
  }
  return out;
}

}  // namespace phaco::compare
