#pragma once
// The run report as one self-contained HTML page (issue 7 item 5; docs/report.md): what a trainee
// reads after a drill. It reads the JSON that `phaco run FILE --report RUN.json` writes (the run
// report contract of issue 7: drill, scenario, metrics, targets, score_terms, events, series) and
// writes nothing but the returned string.
//
// The page shows: a title (drill, scenario, date), the 0-100 score with its per-term breakdown,
// every metric against its target (met / missed), the events, and plots drawn with OpenCV through
// the perf chart library and inlined as PNG data: URIs (no external resource, no script):
//   - contact force over time per hand and its distribution, tool speed over time and its
//     distribution (seed 000 §6, Fig. 11 (a), (b));
//   - both hands' paths seen from above (x-y, the microscope view) and from the side (x-z), with
//     the samples in contact marked (Fig. 11 (c));
//   - the rhexis outline against the target circle band (capsulorhexis);
//   - the trench seen from above: removed material as a depth-coloured scatter inside the nucleus
//     circle (phaco-sculpting).
// Every section tolerates missing fields (older report files, other drills): it is left out with a
// short note. Fields present with the wrong type are an InputError naming the field, e.g.
// "series.hands.left.force_mN: expected an array of numbers" (the caller adds the file name).
#include <cstdint>
#include <nlohmann/json.hpp>
#include <span>
#include <string>

namespace phaco::report {

// The whole page (UTF-8 HTML5). Throws InputError when `run` is not an object or a field has the
// wrong type; never for a missing field. `extra_sections` (HTML, e.g. compare_section.hpp's) goes
// after the plots, before the footer.
std::string html_report(const nlohmann::json& run, const std::string& extra_sections = {});

// RFC 4648 base64 with padding, for the inlined images.
std::string base64_encode(std::span<const std::uint8_t> bytes);

}  // namespace phaco::report
