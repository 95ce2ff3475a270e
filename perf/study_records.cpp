// phaco-perf records (issue 21): stations syncing to one PostgreSQL server at once. For 1, 4 and
// 16 stations (processes), each with 200 records of its own, all start their `sync` together;
// the study reports records per second over the whole upload, each batch's latency (the centre's
// transaction, p50/p99/max) and checks that every record is at the centre exactly once.
//
// The server is the throwaway cluster of scripts/pg_test_cluster.sh (a Unix socket, fsync off:
// what is measured is the protocol, the SQL and the contention, not this machine's disk), or an
// administrator's URI given with --pg (a database is made and dropped on it).
#include <libpq-fe.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "engine/core/error.hpp"
#include "engine/records/records.hpp"
#include "engine/records/sync.hpp"
#include "perf/plot.hpp"
#include "perf/report.hpp"
#include "perf/studies.hpp"

namespace phaco::perf {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

std::string sh_quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

void admin(const std::string& uri, const std::string& sql) {
  PGconn* c = PQconnectdb(uri.c_str());
  PGresult* r = PQexec(c, sql.c_str());
  const bool ok = PQresultStatus(r) == PGRES_COMMAND_OK;
  const std::string why = ok ? "" : PQerrorMessage(c);
  PQclear(r);
  PQfinish(c);
  if (!ok) throw InputError("records: " + sql + ": " + why);
}

int64_t count(const std::string& uri, const char* sql) {
  PGconn* c = PQconnectdb(uri.c_str());
  PGresult* r = PQexec(c, sql);
  const int64_t n = PQresultStatus(r) == PGRES_TUPLES_OK ? std::atoll(PQgetvalue(r, 0, 0)) : -1;
  PQclear(r);
  PQfinish(c);
  return n;
}

// A station's file of `n` records of a realistic size (a scenario with tracks, a report with
// series: about 40 kB each, as a 60-s capsulorhexis record is).
void make_station(const fs::path& file, int n, int station) {
  std::vector<SessionRecord> records;
  for (int i = 0; i < n; ++i) {
    SessionRecord r;
    r.trainee = "trainee " + std::to_string(station % 8);
    r.drill = i % 2 ? "capsulorhexis" : "phaco_sculpting";
    r.scenario_name = "station " + std::to_string(station);
    char t[32];
    std::snprintf(t, sizeof t, "2026-11-%02dT%02d:%02d:00.000Z", 1 + i / 60 % 28, i % 24, i % 60);
    r.started_utc = r.finished_utc = t;
    r.score = 50 + i % 50;
    r.metrics = {{"score", *r.score}, {"rhexis.diameter_mm", 5.2}, {"time_s", 61.5}};
    r.state_hash = "0123456789abcdef";
    r.recording = {{"hands", {{"right", {{"track", std::vector<double>(1500, 1.25)}}}}}};
    r.report = {{"series", {{"force_mN", std::vector<double>(3000, 3.5)}}}};
    r.uuid = new_record_uuid();
    records.push_back(std::move(r));
  }
  RecordStore(file).add_missing(records);
}

struct Level {
  int stations = 0;
  double wall_s = 0, records_per_s = 0;
  std::vector<double> batch_ms;
  int failures = 0;
  int64_t at_centre = 0, distinct = 0;
};

Level run_level(const std::string& uri, const fs::path& dir, int stations, int each, int batch) {
  std::vector<fs::path> files;
  for (int s = 0; s < stations; ++s) {
    files.push_back(dir /
                    ("station" + std::to_string(stations) + "_" + std::to_string(s) + ".sqlite"));
    make_station(files.back(), each, s);
  }
  Level l;
  l.stations = stations;
  int go[2];
  if (pipe(go) != 0) throw std::runtime_error("records: pipe failed");
  std::vector<pid_t> children;
  for (int s = 0; s < stations; ++s) {
    const pid_t child = fork();
    if (child < 0) throw std::runtime_error("records: fork failed");
    if (child == 0) {
      close(go[1]);
      char c;
      // Every station waits for the start signal, then syncs: they arrive at once.
      const bool started = read(go[0], &c, 1) >= 0;
      int code = started ? 0 : 6;
      try {
        RecordStore st(files[static_cast<size_t>(s)]);
        RecordStore centre(uri);
        SyncOptions o;
        o.batch = static_cast<size_t>(batch);
        std::vector<double> ms;
        auto t = Clock::now();
        o.progress = [&](size_t) {
          const auto now = Clock::now();
          ms.push_back(std::chrono::duration<double, std::milli>(now - t).count());
          t = now;
        };
        const SyncResult r = sync_records(st, centre, o);
        std::ofstream out(files[static_cast<size_t>(s)].string() + ".ms");
        for (double v : ms) out << v << "\n";
        if (r.uploaded != static_cast<size_t>(each)) code = 4;
      } catch (const std::exception& e) {
        std::fprintf(stderr, "records: station %d: %s\n", s, e.what());
        code = 5;
      }
      _exit(code);
    }
    children.push_back(child);
  }
  close(go[0]);
  const auto t0 = Clock::now();
  close(go[1]);  // EOF: every station starts
  for (const pid_t c : children) {
    int status = 0;
    waitpid(c, &status, 0);
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) ++l.failures;
  }
  l.wall_s = std::chrono::duration<double>(Clock::now() - t0).count();
  l.records_per_s = stations * each / l.wall_s;
  for (const fs::path& f : files) {
    std::ifstream in(f.string() + ".ms");
    for (double v; in >> v;) l.batch_ms.push_back(v);
  }
  std::sort(l.batch_ms.begin(), l.batch_ms.end());
  l.at_centre = count(uri, "SELECT count(*) FROM records");
  l.distinct = count(uri, "SELECT count(DISTINCT uuid) FROM records");
  return l;
}

double quantile(const std::vector<double>& sorted, double q) {
  if (sorted.empty()) return 0;
  return sorted[std::min(sorted.size() - 1, static_cast<size_t>(q * double(sorted.size())))];
}

}  // namespace

void run_records(const StudyOptions& options) {
  std::string admin_uri;
  for (size_t i = 0; i < options.extra.size(); ++i) {
    if (options.extra[i] == "--pg" && i + 1 < options.extra.size()) {
      admin_uri = options.extra[++i];
    } else {
      throw InputError("records: unknown option '" + options.extra[i] + "'");
    }
  }
  const fs::path dir =
      fs::temp_directory_path() / ("phaco-perf-records-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const fs::path cluster = dir / "cluster";
  const std::string script = std::string(PHACO_SOURCE_DIR) + "/scripts/pg_test_cluster.sh";
  if (admin_uri.empty()) {
    FILE* p = popen((sh_quote(script) + " start " + sh_quote(cluster.string())).c_str(), "r");
    if (!p) throw InputError("records: cannot start a PostgreSQL cluster");
    char line[1024];
    while (std::fgets(line, sizeof line, p)) {
      std::string s = line;
      if (s.rfind("PHACO_TEST_PG_URI='", 0) == 0) admin_uri = s.substr(19, s.rfind('\'') - 19);
    }
    if (pclose(p) != 0 || admin_uri.empty())
      throw InputError("records: cannot start a PostgreSQL cluster with " + script +
                       " (Debian package postgresql)");
  }
  const std::string load = load_note();
  const int each = 200, batch = 20;
  std::vector<int> levels = options.quick ? std::vector<int>{1, 4} : std::vector<int>{1, 4, 16};
  std::vector<Level> results;
  std::string failed;
  Progress progress(static_cast<int>(levels.size()));
  try {
    for (int stations : levels) {
      progress.step("records: " + std::to_string(stations) + " station(s)");
      const std::string db =
          "phaco_perf_" + std::to_string(getpid()) + "_" + std::to_string(stations);
      admin(admin_uri, "CREATE DATABASE " + db);
      const size_t slash = admin_uri.find("/postgres?");
      const std::string uri = slash == std::string::npos ? admin_uri
                                                         : admin_uri.substr(0, slash) + "/" + db +
                                                               admin_uri.substr(slash + 9);
      results.push_back(run_level(uri, dir, stations, each, batch));
      admin(admin_uri, "DROP DATABASE " + db + " WITH (FORCE)");
      const Level& l = results.back();
      if (l.failures || l.at_centre != int64_t(stations) * each || l.distinct != l.at_centre)
        failed += std::to_string(stations) + " stations: " + std::to_string(l.at_centre) +
                  " records at the centre (" + std::to_string(l.distinct) + " distinct), " +
                  std::to_string(l.failures) + " station(s) failed; ";
    }
  } catch (...) {
    std::system((sh_quote(script) + " remove " + sh_quote(cluster.string())).c_str());
    throw;
  }
  progress.finish();
  std::system((sh_quote(script) + " remove " + sh_quote(cluster.string()) + " >/dev/null").c_str());
  fs::remove_all(dir);

  const fs::path out = options.out_dir / "results";
  Table t;
  t.columns = {"stations",     "records",      "wall_s",    "records_per_s", "batch_p50_ms",
               "batch_p99_ms", "batch_max_ms", "at_centre", "distinct"};
  Chart thr{.title = "Records: stations syncing to one server at once",
            .x = {.label = "stations (processes)"},
            .y = {.label = "records per second, all stations", .min = 0.0}};
  Chart lat{.title = "Records: latency of one batch of 20 (the centre's transaction)",
            .x = {.label = "stations (processes)"},
            .y = {.label = "batch latency (ms)", .min = 0.0}};
  Series rate{.name = "throughput"}, p50{.name = "p50"}, p99{.name = "p99"};
  std::string md = "## Records: stations syncing to a training centre\n\n";
  md += "Measured by `phaco-perf records" + std::string(options.quick ? " --quick" : "") + "`, " +
        load +
        ". Each station is a process with its own SQLite file of 200 records of about 40 kB (a "
        "scenario with its tracks and a report with its series, as a one-minute drill's); all "
        "stations start `phaco sync` together against one PostgreSQL server (Debian's, on a Unix "
        "socket of this machine, fsync off: the protocol, SQL and contention are measured, not "
        "the disk), batches of 20 records, each one transaction. The check: every record at the "
        "centre exactly once.\n\n";
  md +=
      "| stations | records | wall (s) | records/s | batch p50 (ms) | batch p99 (ms) | batch max "
      "(ms) | at the centre (distinct) |\n|---:|---:|---:|---:|---:|---:|---:|---|\n";
  for (const Level& l : results) {
    const double q50 = quantile(l.batch_ms, 0.5), q99 = quantile(l.batch_ms, 0.99),
                 mx = l.batch_ms.empty() ? 0 : l.batch_ms.back();
    t.add({double(l.stations), double(l.stations * each), l.wall_s, l.records_per_s, q50, q99, mx,
           double(l.at_centre), double(l.distinct)});
    rate.x.push_back(l.stations), rate.y.push_back(l.records_per_s);
    p50.x.push_back(l.stations), p50.y.push_back(q50);
    p99.x.push_back(l.stations), p99.y.push_back(q99);
    md += "| " + std::to_string(l.stations) + " | " + std::to_string(l.stations * each) + " | " +
          fmt("%.2f", l.wall_s) + " | " + fmt("%.0f", l.records_per_s) + " | " + fmt("%.1f", q50) +
          " | " + fmt("%.1f", q99) + " | " + fmt("%.1f", mx) + " | " + std::to_string(l.at_centre) +
          " (" + std::to_string(l.distinct) + ") |\n";
  }
  thr.series = {rate};
  lat.series = {p50, p99};
  save_chart(thr, out / "records_throughput.png");
  save_chart(lat, out / "records_latency.png");
  write_csv(t, out / "records.csv");
  write_json(t, out / "records.json");
  md +=
      "\n![records throughput](results/records_throughput.png)\n\n"
      "![records latency](results/records_latency.png)\n\n";
  md += failed.empty() ? "Check passed: every record at the centre once.\n"
                       : "**Check failed:** " + failed + "\n";
  write_section(out, "records", md);
  if (!failed.empty()) throw CheckFailed("records: " + failed);
}

}  // namespace phaco::perf
