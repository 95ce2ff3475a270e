// perf/report: CSV/JSON writing and RESULTS.md assembly in a fixed order from the sections present.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "perf/report.hpp"

namespace phaco::perf {
namespace {

namespace fs = std::filesystem;

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

struct TempDir {
  fs::path path = fs::temp_directory_path() / ("phaco_test_report_" + std::to_string(::getpid()));
  TempDir() { fs::create_directories(path); }
  ~TempDir() { fs::remove_all(path); }
};

TEST(Report, CsvAndJsonCarryEveryCell) {
  TempDir dir;
  Table t;
  t.columns = {"method", "ns", "note"};
  t.add({std::string("plain step"), 7.5, std::string("a, \"quoted\" note")});
  t.add({std::string("nan"), std::numeric_limits<double>::quiet_NaN(), std::string("")});
  EXPECT_THROW(t.add({1.0}), std::invalid_argument);
  write_csv(t, dir.path / "t.csv");
  write_json(t, dir.path / "t.json");
  EXPECT_EQ(slurp(dir.path / "t.csv"),
            "method,ns,note\nplain step,7.5,\"a, \"\"quoted\"\" note\"\nnan,,\n");
  const auto j = nlohmann::json::parse(slurp(dir.path / "t.json"));
  ASSERT_EQ(j.size(), 2u);
  EXPECT_EQ(j[0]["method"], "plain step");
  EXPECT_DOUBLE_EQ(j[0]["ns"].get<double>(), 7.5);
  EXPECT_TRUE(j[1]["ns"].is_null());
}

TEST(Report, ResultsAssembledInFixedOrderKeepingOtherSections) {
  TempDir dir;
  write_section(dir.path, "membrane", "## Membrane\n\nm\n");
  write_section(dir.path, "zeta", "## Zeta\n");
  write_section(dir.path, "foundation", "## Foundation\n\nf\n");
  const std::string md = assemble_results(dir.path, "| CPU | x |\n");
  const size_t machine = md.find("## Machine"), f = md.find("## Foundation"),
               m = md.find("## Membrane"), z = md.find("## Zeta");
  ASSERT_NE(machine, std::string::npos);
  ASSERT_NE(f, std::string::npos);
  ASSERT_NE(m, std::string::npos);
  ASSERT_NE(z, std::string::npos);
  EXPECT_LT(machine, f);
  EXPECT_LT(f, m);
  EXPECT_LT(m, z);  // unknown studies after the known ones
  EXPECT_EQ(md.find("## Bandwidth"), std::string::npos);
  // Rewriting one section leaves the others.
  write_section(dir.path, "membrane", "## Membrane\n\nnew\n");
  const std::string again = assemble_results(dir.path, "| CPU | x |\n");
  EXPECT_NE(again.find("new"), std::string::npos);
  EXPECT_NE(again.find("## Foundation\n\nf"), std::string::npos);
}

// The interval studies report repeated runs with: Student's t on n − 1 degrees of freedom, checked
// against values worked by hand.
TEST(Report, MeanIntervalIsStudentsT) {
  // {1, 2, 3}: mean 2, s = 1, half-width t(2) · s / √3 = 4.303 / 1.732.
  const MeanInterval three = mean_interval95({1.0, 2.0, 3.0});
  EXPECT_DOUBLE_EQ(three.mean, 2.0);
  EXPECT_NEAR(three.hi - three.mean, 4.303 / std::sqrt(3.0), 1e-9);
  EXPECT_NEAR(three.mean - three.lo, 4.303 / std::sqrt(3.0), 1e-9);
  // Equal values: no spread, a point interval.
  const MeanInterval same = mean_interval95({1.5, 1.5, 1.5, 1.5});
  EXPECT_DOUBLE_EQ(same.lo, 1.5);
  EXPECT_DOUBLE_EQ(same.hi, 1.5);
  // One value: the mean, and an interval that says nothing.
  const MeanInterval one = mean_interval95({0.9});
  EXPECT_DOUBLE_EQ(one.mean, 0.9);
  EXPECT_TRUE(std::isinf(one.lo) && std::isinf(one.hi));
  EXPECT_TRUE(std::isnan(mean_interval95({}).mean));
}

}  // namespace
}  // namespace phaco::perf
