#pragma once
// The records tests' sample: a finished capsulorhexis with every column filled, the same for the
// SQLite and the PostgreSQL backend so both are held to one round trip.
#include <string>

#include "engine/records/records.hpp"

namespace phaco::test {

inline SessionRecord sample_record(const std::string& trainee, const std::string& started,
                                   double score) {
  SessionRecord r;
  r.trainee = trainee;
  r.drill = "capsulorhexis";
  r.scenario_name = "capsulorhexis demo";
  r.started_utc = started;
  r.finished_utc = started;  // same second: allowed
  r.settings = {{"dt_s", 1.0 / 120.0}, {"seed", 7}, {"eye", {{"level", 2}}}};
  r.metrics = {{"rhexis.diameter_mm", 5.25}, {"rhexis.complete", true}, {"score", score}};
  r.score = score;
  r.state_hash = "0123456789abcdef";
  r.recording = {
      {"drill", "capsulorhexis"}, {"dt_s", 1.0 / 120.0}, {"hands", nlohmann::json::object()}};
  r.report = {{"state_hash", "0123456789abcdef"}, {"frames", 10}};
  return r;
}

}  // namespace phaco::test
