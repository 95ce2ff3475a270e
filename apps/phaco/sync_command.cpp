#include "apps/phaco/sync_command.hpp"

#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <nlohmann/json.hpp>

#include "apps/phaco/args.hpp"
#include "apps/phaco/commands.hpp"
#include "engine/core/error.hpp"
#include "engine/records/record_location.hpp"
#include "engine/records/record_run.hpp"
#include "engine/records/sync.hpp"

namespace phaco::cli {

namespace {

// Exit code when the centre refused some records for their content (the rest were uploaded).
constexpr int kSomeRefused = 3;

size_t batch_of(const Args& a) {
  const auto text = a.option("--batch");
  if (!text) return SyncOptions{}.batch;
  size_t n = 0;
  const auto [end, ec] = std::from_chars(text->data(), text->data() + text->size(), n);
  if (ec != std::errc{} || end != text->data() + text->size() || n < 1 || n > 10000)
    throw InputError("sync: --batch expects a whole number 1..10000, got '" + *text + "'");
  return n;
}

}  // namespace

int sync(const std::vector<std::string>& raw) {
  const Args a = parse_args("sync", raw, {"--to", "--db", "--batch"}, {"--all", "--json"});
  if (!a.positional.empty())
    throw InputError("sync: unexpected argument '" + a.positional[0] + "'");
  std::string to;
  if (auto t = a.option("--to")) {
    to = *t;
  } else if (const char* env = std::getenv("PHACO_SYNC_TO"); env && *env) {
    to = env;
  } else {
    throw InputError("sync: give --to postgresql://USER@HOST/DB (or set PHACO_SYNC_TO)");
  }
  if (!is_postgres_uri(to))
    throw InputError("sync: --to expects a postgresql:// URI, got '" + shown_location(to) + "'");
  const std::filesystem::path db =
      a.option("--db") ? std::filesystem::path(*a.option("--db")) : default_records_db();
  if (is_postgres_uri(db.string()))
    throw InputError("sync: --db is the station's own SQLite file, got a server URI");
  SyncOptions options;
  options.batch = batch_of(a);
  options.resend_all = a.flag("--all");
  RecordStore station(db, OpenMode::ExistingOnly);
  RecordStore centre(to, OpenMode::CreateIfMissing);
  const SyncResult r = sync_records(station, centre, options);
  if (a.flag("--json")) {
    const nlohmann::json j = {{"station", station.location()},
                              {"centre", centre.location()},
                              {"pending", r.pending},
                              {"uploaded", r.uploaded},
                              {"already_there", r.already_there},
                              {"refused", r.refused}};
    std::printf("%s\n", j.dump(2).c_str());
  } else {
    std::printf("sync %s -> %s: %zu to send, %zu uploaded, %zu already there, %zu refused\n",
                station.location().c_str(), centre.location().c_str(), r.pending, r.uploaded,
                r.already_there, r.refused.size());
    for (const std::string& why : r.refused) std::printf("  refused %s\n", why.c_str());
  }
  return r.refused.empty() ? kOk : kSomeRefused;
}

}  // namespace phaco::cli
