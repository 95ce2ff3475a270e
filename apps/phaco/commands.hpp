#pragma once
// The headless `phaco` command: one function per subcommand. Each returns the process exit code:
// 0 success, 2 bad input (message on stderr), 1 internal error.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace phaco::cli {

inline constexpr int kOk = 0;
inline constexpr int kInternalError = 1;
inline constexpr int kBadInput = 2;

int validate(const std::vector<std::string>& args);
int mesh(const std::vector<std::string>& args);
int run(const std::vector<std::string>& args);
int graph(const std::vector<std::string>& args);

struct Args;
// `run`'s output: the JSON report with --json, else the summary and where --report wrote it.
void print_run(const Args& a, const nlohmann::json& report, const std::string& summary);
// `run`'s records (docs/records.md): the database --record/--trainee name, checked before the run
// (the trainee's name acceptable, the database opening); none without either. Throws InputError.
std::optional<std::filesystem::path> record_target(const Args& a);

}  // namespace phaco::cli
