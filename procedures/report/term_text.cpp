#include "procedures/report/term_text.hpp"

#include <array>
#include <cmath>
#include <utility>

namespace phaco::report {

using nlohmann::json;

namespace {

// Suffix → unit, longest first so "_mm_s" wins over "_s".
constexpr std::array<std::pair<const char*, const char*>, 7> kUnits = {{{"_mm_s", "mm/s"},
                                                                        {"_pct_s", "% s"},
                                                                        {"_deg", "°"},
                                                                        {"_mm", "mm"},
                                                                        {"_mN", "mN"},
                                                                        {"_us", "µs"},
                                                                        {"_s", "s"}}};

bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() > tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

// The key without its unit suffix (the segment that carries one), and the unit.
std::pair<std::string, std::string> split_unit(const std::string& metric) {
  size_t end = metric.size();
  for (;;) {
    const size_t start = metric.rfind('.', end == 0 ? 0 : end - 1);
    const std::string seg = metric.substr(start == std::string::npos ? 0 : start + 1,
                                          end - (start == std::string::npos ? 0 : start + 1));
    for (const auto& [suffix, unit] : kUnits)
      if (ends_with(seg, suffix))
        return {metric.substr(0, end - std::string(suffix).size()) + metric.substr(end), unit};
    if (start == std::string::npos || start == 0) return {metric, ""};
    end = start;
  }
}

std::optional<fields::Band> band_of(const json& t) {
  if (!t.is_object()) return std::nullopt;
  fields::Band b;
  if (const json* lo = fields::member(t, "min"); lo && lo->is_number()) b.min = lo->get<double>();
  if (const json* hi = fields::member(t, "max"); hi && hi->is_number()) b.max = hi->get<double>();
  if (!b.min && !b.max) return std::nullopt;
  return b;
}

std::string with_unit(const std::string& text, const std::string& unit) {
  if (unit.empty() || text == "—") return text;
  return text + (unit == "°" ? "" : " ") + unit;
}

}  // namespace

std::optional<double> as_number(const json& j) {
  if (j.is_number()) return j.get<double>();
  if (j.is_boolean()) return j.get<bool>() ? 1.0 : 0.0;
  return std::nullopt;
}

std::string metric_unit(const std::string& metric) {
  return split_unit(metric).second;
}

std::string metric_label(const std::string& metric) {
  auto [name, unit] = split_unit(metric);
  for (char& c : name)
    if (c == '_' || c == '.') c = ' ';
  return unit.empty() ? name : name + " (" + unit + ")";
}

std::string band_text(const fields::Band& b, const std::string& unit) {
  if (b.min && b.max) return with_unit(fields::fmt(*b.min) + " – " + fields::fmt(*b.max), unit);
  if (b.min) return with_unit("≥ " + fields::fmt(*b.min), unit);
  if (b.max) return with_unit("≤ " + fields::fmt(*b.max), unit);
  return "—";
}

bool within(double v, const fields::Band& b) {
  const auto slack = [](double bound) { return 1e-9 * (1 + std::fabs(bound)); };
  return (!b.min || v >= *b.min - slack(*b.min)) && (!b.max || v <= *b.max + slack(*b.max));
}

std::string target_text(const json& t, const std::string& unit) {
  if (const auto b = band_of(t)) return band_text(*b, unit);
  return t.is_null() ? "—" : fields::scalar_text(t);
}

std::optional<bool> meets(const json& value, const json& target) {
  const auto v = as_number(value);
  const auto b = band_of(target);
  if (!v || !b) return std::nullopt;
  return within(*v, *b);
}

TermText term_text(const fields::Term& t) {
  TermText r;
  const std::string unit = metric_unit(t.metric);
  r.label = t.metric.empty() ? "(unnamed)" : metric_label(t.metric);
  r.value = t.value.is_number() ? with_unit(fields::scalar_text(t.value), unit)
                                : fields::scalar_text(t.value);
  r.target = target_text(t.target, unit);
  r.weight = t.weight ? fields::fmt(*t.weight) : "—";
  r.points = t.points ? fields::fmt(*t.points) : "—";
  r.met = meets(t.value, t.target);
  return r;
}

}  // namespace phaco::report
