#pragma once
// Finished drills as xAPI 2.0 statements (IEEE 9274.1.1-2023; issue 21 item 3), for a
// learning-management system's record store (LRS).
//
// One statement per record:
//   id       the record's uuid, so a record exported twice is one statement to an LRS;
//   actor    an Agent identified by an account (the centre's home page, the trainee's name);
//   verb     ADL "completed";
//   object   the drill as an Activity with a stable IRI (kXapiDrillIri + drill name), of type
//            ADL "simulation";
//   result   score.scaled/raw/min/max (when the drill scores), success (score ≥ kPassScore),
//            completion true, duration (ISO 8601, finished − started), and every metric with its
//            unit as the extension kXapiMetricsIri;
//   context  platform "OpenPhaco", the scenario, state hash and settings as extensions;
//   timestamp when the drill finished.
// `version` is left out: an LRS sets it (2.0.0) on what it stores, and statements without it are
// valid to 1.0.3 validators too (Learning Locker's, which the tests run, predates 2.0).
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "engine/records/records.hpp"

namespace phaco {

inline constexpr const char* kXapiDrillIri = "https://openphaco.org/xapi/activities/drill/";
inline constexpr const char* kXapiExtensionIri = "https://openphaco.org/xapi/extensions/";
// Whose trainees: the account's home page when no centre's is given.
inline constexpr const char* kXapiDefaultHomePage = "https://openphaco.org/trainees";

// The pass line of `success`, 0–100 points, for every drill until per-drill cut-offs from cohorts
// exist (issue 20, contrasting groups); the cohort dashboard draws the same line.
inline constexpr double kPassScore = 75.0;

// The statement of one record; `home_page`: the centre's IRI for its trainees' accounts.
nlohmann::json record_to_xapi(const SessionRecord& record,
                              const std::string& home_page = kXapiDefaultHomePage);
// ISO 8601 duration of `seconds` ("PT42.125S", "PT1H2M3.5S"); "PT0S" for non-positive.
std::string iso8601_duration(double seconds);

}  // namespace phaco
