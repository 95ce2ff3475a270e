// Records end to end (issue 7 item 4). Two layers:
//  - RecordRun: record_run / history / export_record called in-process after run_scenario, so the
//    store, the export and the replay are checked even before `phaco run --record` exists;
//  - RecordsCli: the `phaco` binary as a trainee meets it (PHACO_BIN): `run --record --trainee`,
//    `history`, `export`, replay of the export, and a run killed with SIGKILL mid-drill.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "apps/phaco/records_commands.hpp"
#include "engine/core/error.hpp"
#include "engine/io/scenario.hpp"
#include "engine/records/records.hpp"
#include "procedures/scene/run.hpp"
#include "tests/apps/cli.hpp"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using phaco::test::phaco;
using phaco::test::read_text;
using phaco::test::temp_dir;
using phaco::test::write_text;

const fs::path kIncisionDemo =
    fs::path(PHACO_SOURCE_DIR) / "data/scenarios/corneal_incision_demo.json";

using Result = phaco::test::ShellResult;

// Meshes shared by every test of this executable (generated once, then loaded).
fs::path cache_dir() {
  static const fs::path d = [] {
    const fs::path c =
        fs::temp_directory_path() / ("phaco-records-cache-" + std::to_string(::getpid()));
    fs::create_directories(c);
    return c;
  }();
  return d;
}

// Removes the shared mesh cache when the executable ends.
class CacheCleanup : public testing::Environment {
 public:
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(cache_dir(), ec);
  }
};
const auto* const kCacheCleanup = testing::AddGlobalTestEnvironment(new CacheCleanup);

json read_json(const fs::path& file) {
  std::ifstream in(file);
  return json::parse(in);
}

// Minimal well-formedness: one root, tags balanced and properly nested, attribute values quoted,
// only the five predefined entities or character references, no raw '<' or '&' in text.
// Returns "" when well-formed, else what is wrong. Also collects each element's name.
std::string check_xml(const std::string& xml, std::vector<std::string>* elements = nullptr) {
  size_t i = 0;
  if (xml.rfind("<?xml", 0) == 0) i = xml.find("?>") + 2;
  std::vector<std::string> stack;
  int roots = 0;
  auto check_entities = [](std::string_view text) -> std::string {
    for (size_t p = 0; (p = text.find('&', p)) != std::string_view::npos; ++p) {
      const size_t semi = text.find(';', p);
      if (semi == std::string_view::npos) return "unterminated entity";
      const std::string_view e = text.substr(p + 1, semi - p - 1);
      if (e != "amp" && e != "lt" && e != "gt" && e != "quot" && e != "apos" &&
          !(e.size() > 1 && e[0] == '#')) {
        return "unknown entity &" + std::string(e) + ";";
      }
    }
    return "";
  };
  while (i < xml.size()) {
    const size_t lt = xml.find('<', i);
    const std::string_view text(xml.data() + i, (lt == std::string::npos ? xml.size() : lt) - i);
    if (auto e = check_entities(text); !e.empty()) return e;
    if (stack.empty() && text.find_first_not_of(" \n\r\t") != std::string_view::npos)
      return "text outside the root";
    if (lt == std::string::npos) break;
    const size_t gt = xml.find('>', lt);
    if (gt == std::string::npos) return "unterminated tag";
    std::string tag = xml.substr(lt + 1, gt - lt - 1);
    if (tag.find('<') != std::string::npos) return "'<' inside a tag";
    i = gt + 1;
    if (!tag.empty() && tag[0] == '/') {
      if (stack.empty() || stack.back() != tag.substr(1))
        return "mismatched </" + tag.substr(1) + ">";
      stack.pop_back();
      continue;
    }
    const bool empty = !tag.empty() && tag.back() == '/';
    if (empty) tag.pop_back();
    const std::string name = tag.substr(0, tag.find(' '));
    if (name.empty()) return "empty tag name";
    // Attributes: name="value" pairs, quotes balanced.
    size_t quotes = 0;
    for (char c : tag) quotes += c == '"';
    if (quotes % 2 != 0) return "unbalanced quotes in <" + name + ">";
    if (auto e = check_entities(tag); !e.empty()) return e;
    if (elements) elements->push_back(name);
    if (stack.empty()) ++roots;
    if (!empty) stack.push_back(name);
  }
  if (!stack.empty()) return "unclosed <" + stack.back() + ">";
  if (roots != 1) return "expected one root element, got " + std::to_string(roots);
  return "";
}

// The text of the first <tag>...</tag>.
std::string element_text(const std::string& xml, const std::string& tag) {
  const size_t b = xml.find("<" + tag + ">");
  if (b == std::string::npos) return "";
  const size_t s = b + tag.size() + 2;
  return xml.substr(s, xml.find("</" + tag + ">", s) - s);
}

TEST(RecordsXmlChecker, CatchesBrokenXml) {  // the checker below must be able to fail
  EXPECT_EQ(check_xml("<a><b x=\"1\">t &amp; u</b><c/></a>"), "");
  EXPECT_NE(check_xml("<a><b></a></b>"), "");
  EXPECT_NE(check_xml("<a>x & y</a>"), "");
  EXPECT_NE(check_xml("<a x=\"1></a>"), "");
  EXPECT_NE(check_xml("<a></a><b></b>"), "");
}

// --- In-process: record_run, history, export_record, replay --------------------------------

phaco::RunReport run_demo(const phaco::Scenario& s) {
  phaco::SceneOptions o;
  o.cache_dir = cache_dir();
  return phaco::run_scenario(s, o);
}

TEST(RecordRun, RecordsTwoRunsThenHistoryExportAndReplay) {
  const fs::path dir = temp_dir("inproc");
  const fs::path db = dir / "sub" / "records.sqlite";  // the directory is created on first record
  const phaco::Scenario demo = phaco::load_scenario(kIncisionDemo);
  const json report = phaco::to_json(run_demo(demo));
  ASSERT_FALSE(report["metrics"].empty()) << "nothing for the replay to reproduce";
  const int64_t first = phaco::cli::record_run(db, "Ana Ruiz", demo, report);
  const int64_t second = phaco::cli::record_run(db, "Ana Ruiz", demo, report);
  EXPECT_EQ(second, first + 1);

  {
    const phaco::RecordStore store(db, phaco::OpenMode::ExistingOnly);
    const auto rows = store.records_of("Ana Ruiz");
    ASSERT_EQ(rows.size(), 2u);
    EXPECT_EQ(rows[0].id, first);
    EXPECT_LE(rows[0].started_utc, rows[1].started_utc);
    EXPECT_EQ(rows[0].drill, "corneal_incision");
    EXPECT_EQ(rows[0].scenario_name, "corneal incision demo");
    EXPECT_EQ(rows[0].state_hash, report["state_hash"]);
    EXPECT_EQ(rows[0].metrics, report["metrics"]);
    EXPECT_EQ(rows[0].report, report);
    EXPECT_EQ(rows[0].settings["eye"]["level"], demo.eye.level);
    EXPECT_EQ(rows[0].settings["seed"], demo.seed);
    EXPECT_FALSE(rows[0].settings.contains("hands"));
    EXPECT_FALSE(rows[0].settings.contains("drill"));
  }

  testing::internal::CaptureStdout();
  EXPECT_EQ(phaco::cli::history({"Ana Ruiz", "--db", db.string()}), 0);
  const std::string listing = testing::internal::GetCapturedStdout();
  EXPECT_NE(listing.find("2 session(s)"), std::string::npos) << listing;
  EXPECT_NE(listing.find("corneal_incision"), std::string::npos) << listing;

  const fs::path scen = dir / "replay.json", xml = dir / "r.xml", js = dir / "r.json";
  testing::internal::CaptureStdout();
  EXPECT_EQ(
      phaco::cli::export_record({std::to_string(second), "--db", db.string(), "--scenario",
                                 scen.string(), "--xml", xml.string(), "--json", js.string()}),
      0);
  testing::internal::GetCapturedStdout();

  // The exported recording is the scenario that ran, and replaying it reproduces the run.
  const phaco::Scenario replay = phaco::load_scenario(scen);
  EXPECT_EQ(replay, demo);
  const json again = phaco::to_json(run_demo(replay));
  EXPECT_EQ(again["state_hash"], report["state_hash"]);
  EXPECT_EQ(again["metrics"], report["metrics"]);
  EXPECT_EQ(again["frames"], report["frames"]);

  const std::string x = read_text(xml);
  EXPECT_EQ(check_xml(x), "") << x;
  EXPECT_EQ(element_text(x, "trainee"), "Ana Ruiz");
  EXPECT_EQ(element_text(x, "state_hash"), report["state_hash"].get<std::string>());
  const json j = read_json(js);
  EXPECT_EQ(j["id"], second);
  EXPECT_EQ(j["report"], report);

  // Bad input names what is wrong.
  try {
    phaco::cli::history({"Nobody", "--db", db.string()});
    ADD_FAILURE() << "unknown trainee accepted";
  } catch (const phaco::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("trainees: Ana Ruiz"), std::string::npos) << e.what();
  }
  EXPECT_THROW(phaco::cli::export_record({"99", "--db", db.string(), "--json", js.string()}),
               phaco::InputError);
  EXPECT_THROW(phaco::cli::record_run(db, "", demo, report), phaco::InputError);
  EXPECT_THROW(phaco::cli::record_run(db, "tab\there", demo, report), phaco::InputError);
  fs::remove_all(dir);
}

TEST(RecordRun, RecordTargetIsCheckedBeforeTheDrill) {
  const fs::path dir = temp_dir("target");
  const fs::path db = dir / "new" / "records.sqlite";
  EXPECT_THROW(phaco::cli::check_record_target(db, ""), phaco::InputError);
  EXPECT_FALSE(fs::exists(db)) << "a bad name is refused before anything is created";
  phaco::cli::check_record_target(db, "ana");
  EXPECT_TRUE(fs::exists(db));
  const fs::path not_db = dir / "notes.txt";
  std::ofstream(not_db) << std::string(2000, 'n');
  try {
    phaco::cli::check_record_target(not_db, "ana");
    ADD_FAILURE() << "a text file accepted as a records database";
  } catch (const phaco::InputError& e) {
    EXPECT_NE(std::string(e.what()).find(not_db.string()), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

// --- The binary ------------------------------------------------------------------------------

std::string cache_opt() {
  return " --cache-dir " + cache_dir().string();
}

TEST(RecordsCli, RecordHistoryExportAndReplay) {
  const fs::path dir = temp_dir("cli");
  const fs::path db = dir / "records.sqlite";
  const std::string rec = " --record " + db.string() + " --trainee ana" + cache_opt();
  const Result one =
      phaco("run " + kIncisionDemo.string() + rec + " --report " + (dir / "r1.json").string());
  ASSERT_EQ(one.code, 0) << one.output;
  const Result two =
      phaco("run " + kIncisionDemo.string() + rec + " --report " + (dir / "r2.json").string());
  ASSERT_EQ(two.code, 0) << two.output;
  const json r1 = read_json(dir / "r1.json");
  ASSERT_FALSE(r1["metrics"].empty()) << "nothing for the replay to reproduce";

  const Result hist = phaco("history ana --db " + db.string());
  ASSERT_EQ(hist.code, 0) << hist.output;
  EXPECT_NE(hist.output.find("2 session(s)"), std::string::npos) << hist.output;
  const Result hj = phaco("history ana --json", "PHACO_RECORDS_DB=" + db.string());
  ASSERT_EQ(hj.code, 0) << hj.output;
  const json h = json::parse(hj.output);
  ASSERT_EQ(h["records"].size(), 2u);
  EXPECT_EQ(h["records"][0]["drill"], "corneal_incision");
  EXPECT_LE(h["records"][0]["started_utc"].get<std::string>(),
            h["records"][1]["started_utc"].get<std::string>());
  EXPECT_EQ(h["trend"]["corneal_incision"]["sessions"], 2);
  const int64_t id = h["records"][0]["id"];

  const fs::path scen = dir / "replay.json", xml = dir / "r.xml", js = dir / "r.json";
  const Result ex = phaco("export " + std::to_string(id) + " --db " + db.string() + " --scenario " +
                          scen.string() + " --xml " + xml.string() + " --json " + js.string());
  ASSERT_EQ(ex.code, 0) << ex.output;
  const Result replay =
      phaco("run " + scen.string() + " --report " + (dir / "r3.json").string() + cache_opt());
  ASSERT_EQ(replay.code, 0) << replay.output;
  const json r3 = read_json(dir / "r3.json");
  EXPECT_EQ(r3["state_hash"], r1["state_hash"]);
  EXPECT_EQ(r3["metrics"], r1["metrics"]);

  std::vector<std::string> elements;
  const std::string x = read_text(xml);
  EXPECT_EQ(check_xml(x, &elements), "") << x;
  EXPECT_EQ(elements.front(), "openphaco_records");
  EXPECT_EQ(element_text(x, "drill"), "corneal_incision");
  EXPECT_EQ(element_text(x, "state_hash"), r1["state_hash"].get<std::string>());
  const json j = read_json(js);
  EXPECT_EQ(j["trainee"], "ana");
  EXPECT_EQ(j["state_hash"], r1["state_hash"]);
  EXPECT_EQ(j["metrics"], r1["metrics"]);
  fs::remove_all(dir);
}

TEST(RecordsCli, BadInputIsExitTwoNamingTheProblem) {
  const fs::path dir = temp_dir("clibad");
  const fs::path db = dir / "records.sqlite";
  EXPECT_EQ(phaco("history").code, 2);
  const Result none = phaco("history ana --db " + db.string());
  EXPECT_EQ(none.code, 2);
  EXPECT_NE(none.output.find(db.string()), std::string::npos) << none.output;
  EXPECT_FALSE(fs::exists(db)) << "history must not create a database";
  EXPECT_EQ(phaco("export abc --db " + db.string() + " --xml x.xml").code, 2);
  EXPECT_EQ(phaco("export 1 --db " + db.string()).code, 2) << "needs an output";
  const fs::path not_db = dir / "notes.txt";
  std::ofstream(not_db) << std::string(2000, 'n');
  const Result bad = phaco("export 1 --db " + not_db.string() + " --xml " + (dir / "x").string());
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.output.find(not_db.string() + ": "), std::string::npos) << bad.output;
  EXPECT_NE(bad.output.find("not an SQLite database"), std::string::npos) << bad.output;
  fs::remove_all(dir);
}

TEST(RecordsCli, KilledRunLeavesDatabaseReadableWithEarlierRecords) {
  const fs::path dir = temp_dir("kill");
  const fs::path db = dir / "records.sqlite";
  const Result first = phaco("run " + kIncisionDemo.string() + " --record " + db.string() +
                             " --trainee ana --report " + (dir / "r1.json").string() + cache_opt());
  ASSERT_EQ(first.code, 0) << first.output;

  // A long drill: the capsulorhexis demo slowed down twenty times (about 20 s of stepping here,
  // the tool in contact with the capsule throughout), killed well before it ends.
  json scen = read_json(fs::path(PHACO_SOURCE_DIR) / "data/scenarios/capsulorhexis_demo.json");
  constexpr double kSlower = 20;
  scen["name"] = "long drill";
  scen["duration_s"] = scen["duration_s"].get<double>() * kSlower;
  for (auto& [hand, h] : scen["hands"].items()) {
    for (auto& sample : h["track"]) sample["t"] = sample["t"].get<double>() * kSlower;
  }
  const fs::path long_file = dir / "long.json";
  std::ofstream(long_file) << scen.dump(2);

  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    const std::string cache = cache_dir().string();
    if (std::freopen("/dev/null", "w", stdout) == nullptr) _exit(126);
    execl(PHACO_BIN, PHACO_BIN, "run", long_file.c_str(), "--record", db.c_str(), "--trainee",
          "ana", "--cache-dir", cache.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));  // mid-drill
  ASSERT_EQ(kill(child, SIGKILL), 0);
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFSIGNALED(status)) << "the long run ended by itself (exit "
                                   << (WIFEXITED(status) ? WEXITSTATUS(status) : -1) << ")";

  const phaco::RecordStore store(db, phaco::OpenMode::ExistingOnly);
  EXPECT_EQ(store.integrity_check(), "ok");
  const auto rows = store.records_of("ana");
  ASSERT_EQ(rows.size(), 1u) << "only the finished drill is stored";
  EXPECT_EQ(rows[0].state_hash, read_json(dir / "r1.json")["state_hash"]);
  const Result hist = phaco("history ana --db " + db.string());
  EXPECT_EQ(hist.code, 0) << hist.output;
  fs::remove_all(dir);
}

}  // namespace
