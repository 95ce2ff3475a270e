#include "procedures/report/report_fields.hpp"

#include <cmath>
#include <cstdio>

#include "engine/core/error.hpp"

namespace phaco::report::fields {

const json* member(const json& object, const char* key) {
  const auto it = object.find(key);
  return it == object.end() ? nullptr : &*it;
}

namespace {

// ---------------------------------------------------------------------------------------------
// Reading, with the field's path in every message.

[[noreturn]] void bad(const std::string& path, const std::string& what) {
  throw InputError(path + ": " + what);
}

std::string join(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

void require_object(const json& j, const std::string& path) {
  if (!j.is_object()) bad(path, "expected an object");
}

double number(const json& j, const std::string& path) {
  if (!j.is_number()) bad(path, "expected a number");
  return j.get<double>();
}

std::string text(const json& j, const std::string& path) {
  if (!j.is_string()) bad(path, "expected a string");
  return j.get<std::string>();
}

std::vector<double> numbers(const json& j, const std::string& path) {
  if (!j.is_array()) bad(path, "expected an array of numbers");
  std::vector<double> v;
  v.reserve(j.size());
  for (const json& e : j) {
    if (!e.is_number()) bad(path, "expected an array of numbers");
    v.push_back(e.get<double>());
  }
  return v;
}

template <size_t N>
std::vector<std::array<double, N>> points(const json& j, const std::string& path,
                                          const char* shape) {
  const std::string expected = std::string("expected an array of ") + shape + " points";
  if (!j.is_array()) bad(path, expected);
  std::vector<std::array<double, N>> v;
  v.reserve(j.size());
  for (size_t i = 0; i < j.size(); ++i) {
    const json& p = j[i];
    if (!p.is_array() || p.size() != N) bad(path + "[" + std::to_string(i) + "]", expected);
    std::array<double, N> a{};
    for (size_t k = 0; k < N; ++k) {
      if (!p[k].is_number()) bad(path + "[" + std::to_string(i) + "]", expected);
      a[k] = p[k].get<double>();
    }
    v.push_back(a);
  }
  return v;
}

std::array<double, 2> pair_of(const json& j, const std::string& path) {
  const std::vector<double> v = numbers(j, path);
  if (v.size() != 2) bad(path, "expected two numbers");
  return {v[0], v[1]};
}

Hand read_hand(const json& j, const std::string& name, const std::string& path) {
  require_object(j, path);
  Hand h;
  h.name = name;
  if (const json* t = member(j, "tool")) h.tool = text(*t, join(path, "tool"));
  if (const json* p = member(j, "pos_mm")) h.pos = points<3>(*p, join(path, "pos_mm"), "[x, y, z]");
  if (const json* s = member(j, "speed_mm_s")) h.speed = numbers(*s, join(path, "speed_mm_s"));
  if (const json* f = member(j, "force_mN")) h.force = numbers(*f, join(path, "force_mN"));
  return h;
}

}  // namespace

Run read_run(const json& j) {
  if (!j.is_object()) bad("(top level)", "expected a JSON object (a run report)");
  Run r;
  if (const json* v = member(j, "drill")) r.drill = text(*v, "drill");
  if (const json* v = member(j, "scenario")) r.scenario = text(*v, "scenario");
  if (const json* v = member(j, "date")) r.date = text(*v, "date");
  if (const json* v = member(j, "state_hash"))
    r.state_hash = v->is_string() ? v->get<std::string>() : v->dump();
  if (const json* v = member(j, "sim_time_s")) r.sim_time_s = number(*v, "sim_time_s");
  if (const json* v = member(j, "frames")) r.frames = number(*v, "frames");
  if (const json* sw = member(j, "software")) {
    require_object(*sw, "software");
    const json* name = member(*sw, "name");
    const json* version = member(*sw, "version");
    const json* revision = member(*sw, "revision");
    r.software = (name ? text(*name, "software.name") : std::string("OpenPhaco")) + " " +
                 (version ? text(*version, "software.version") : std::string("?")) + " (revision " +
                 (revision ? text(*revision, "software.revision") : std::string("unknown")) + ")";
  }

  if (const json* m = member(j, "metrics")) {
    require_object(*m, "metrics");
    r.has_metrics = true;
    for (const auto& [k, v] : m->items()) r.metrics.emplace_back(k, v);
    if (const json* s = member(*m, "score")) r.score = number(*s, "metrics.score");
    if (const json* a = member(*m, "attempted"))
      r.not_attempted = number(*a, "metrics.attempted") <= 0;
  }
  if (const json* c = member(j, "complications")) {
    if (!c->is_array()) bad("complications", "expected an array of {\"name\", ...}");
    for (size_t i = 0; i < c->size(); ++i) {
      const std::string path = "complications[" + std::to_string(i) + "]";
      require_object((*c)[i], path);
      if (const json* v = member((*c)[i], "name"))
        r.complications.push_back(text(*v, join(path, "name")));
    }
  }
  if (const json* t = member(j, "targets")) {
    require_object(*t, "targets");
    r.has_targets = true;
    for (const auto& [k, v] : t->items()) {
      const std::string path = join("targets", k);
      if (!v.is_object()) bad(path, "expected an object {\"min\": a, \"max\": b}");
      Band b;
      if (const json* lo = member(v, "min")) b.min = number(*lo, join(path, "min"));
      if (const json* hi = member(v, "max")) b.max = number(*hi, join(path, "max"));
      r.targets[k] = b;
    }
  }
  if (const json* s = member(j, "score_terms")) {
    if (!s->is_array()) bad("score_terms", "expected an array of terms");
    r.has_terms = true;
    for (size_t i = 0; i < s->size(); ++i) {
      const json& e = (*s)[i];
      const std::string path = "score_terms[" + std::to_string(i) + "]";
      require_object(e, path);
      Term t;
      if (const json* v = member(e, "metric")) t.metric = text(*v, join(path, "metric"));
      if (const json* v = member(e, "value")) t.value = *v;
      if (const json* v = member(e, "target")) t.target = *v;
      if (const json* v = member(e, "weight")) t.weight = number(*v, join(path, "weight"));
      if (const json* v = member(e, "points")) t.points = number(*v, join(path, "points"));
      r.terms.push_back(std::move(t));
    }
  }
  if (const json* ev = member(j, "events")) {
    if (!ev->is_array()) bad("events", "expected an array of events");
    r.has_events = true;
    for (size_t i = 0; i < ev->size(); ++i) {
      const json& e = (*ev)[i];
      const std::string path = "events[" + std::to_string(i) + "]";
      require_object(e, path);
      Event out;
      for (const auto& [k, v] : e.items()) {
        if (k == "t_s")
          out.t_s = number(v, join(path, k));
        else if (k == "kind")
          out.kind = text(v, join(path, k));
        else if (k == "hand")
          out.hand = text(v, join(path, k));
        else
          out.details.emplace_back(k, scalar_text(v));
      }
      r.events.push_back(std::move(out));
    }
  }
  if (const json* s = member(j, "series")) {
    require_object(*s, "series");
    r.has_series = true;
    if (const json* t = member(*s, "t_s")) r.t_s = numbers(*t, "series.t_s");
    if (const json* hs = member(*s, "hands")) {
      require_object(*hs, "series.hands");
      for (const char* name : {"left", "right"}) {
        if (const json* h = member(*hs, name))
          r.hands.push_back(read_hand(*h, name, join("series.hands", name)));
      }
      for (const auto& [k, v] : hs->items()) {
        if (k != "left" && k != "right")
          r.hands.push_back(read_hand(v, k, join("series.hands", k)));
      }
    }
    if (const json* rx = member(*s, "rhexis")) {
      require_object(*rx, "series.rhexis");
      Rhexis out;
      if (const json* o = member(*rx, "outline_mm"))
        out.outline = points<2>(*o, "series.rhexis.outline_mm", "[x, y]");
      if (const json* d = member(*rx, "target_diameter_mm"))
        out.target_diameter = pair_of(*d, "series.rhexis.target_diameter_mm");
      if (const json* c = member(*rx, "target_centre_mm"))
        out.target_centre = pair_of(*c, "series.rhexis.target_centre_mm");
      r.rhexis = std::move(out);
    }
    if (const json* tr = member(*s, "trench")) {
      require_object(*tr, "series.trench");
      Trench out;
      if (const json* p = member(*tr, "removed_xy_depth"))
        out.removed = points<3>(*p, "series.trench.removed_xy_depth", "[x, y, depth_fraction]");
      if (const json* n = member(*tr, "nucleus_radius_mm"))
        out.nucleus_radius = number(*n, "series.trench.nucleus_radius_mm");
      r.trench = std::move(out);
    }
  }
  return r;
}

std::string fmt(double v) {
  if (!std::isfinite(v)) return "n/a";
  char buf[48];
  if (v == std::round(v) && std::fabs(v) < 1e12)
    std::snprintf(buf, sizeof buf, "%.0f", v);
  else
    std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

std::string scalar_text(const json& j) {
  if (j.is_number()) return fmt(j.get<double>());
  if (j.is_boolean()) return j.get<bool>() ? "yes" : "no";
  if (j.is_string()) return j.get<std::string>();
  if (j.is_null()) return "—";
  std::string s = j.dump();
  if (s.size() > 80) s = s.substr(0, 77) + "...";
  return s;
}

}  // namespace phaco::report::fields
