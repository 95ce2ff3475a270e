#pragma once
// One record as the text columns both backends store (issue 21): the JSON columns dumped, and
// read back with an error naming the record and column when a row was edited by hand or damaged.
// Column order is the backends' SELECT order: id, trainee, drill, scenario_name, started_utc,
// finished_utc, settings, metrics, score, state_hash, recording, report, uuid.
#include <array>
#include <cstdint>
#include <optional>
#include <string>

#include "engine/records/records.hpp"

namespace phaco::records {

inline constexpr int kRowColumns = 13;

struct RowText {
  int64_t id = 0;
  std::array<std::string, kRowColumns> columns;  // [0] and [8] (id, score) unused
  std::optional<double> score;
};

RowText row_of(const SessionRecord& record);
// `database`: the shown location, for messages.
SessionRecord record_from_row(const RowText& row, const std::string& database);

}  // namespace phaco::records
