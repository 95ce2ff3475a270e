#include "procedures/trainer/trainer_record.hpp"

#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "engine/core/error.hpp"
#include "engine/records/records.hpp"

namespace phaco {

namespace {

// Forwards every call; what read() returns is also recorded (DeviceRecorder keeps new samples
// only, so repeated reads of one sample are one track sample), with the paused time taken out.
class RecordingDevice final : public Device {
 public:
  RecordingDevice(std::unique_ptr<Device> inner, DeviceRecorder& recorder,
                  const RecordingClock& clock)
      : inner_(std::move(inner)), recorder_(recorder), clock_(clock) {}
  std::string_view name() const override { return inner_->name(); }
  DeviceLimits limits() const override { return inner_->limits(); }
  void start(int64_t now_ns) override { inner_->start(now_ns); }
  void stop() override { inner_->stop(); }
  bool read(int64_t now_ns, DeviceSample& out) override {
    const bool got = inner_->read(now_ns, out);
    // Relaxed: a flag and a total the UI thread sets; a sample recorded one tick late is harmless.
    if (got && !clock_.paused.load(std::memory_order_relaxed)) {
      DeviceSample s = out;
      s.t_ns -= clock_.paused_ns.load(std::memory_order_relaxed);
      recorder_.record(s);
    }
    return got;
  }
  void write_force(const Vec3& force_mn, int64_t now_ns) override {
    inner_->write_force(force_mn, now_ns);
  }
  DeviceHealth health(int64_t now_ns) const override { return inner_->health(now_ns); }
  DeviceCounters counters() const override { return inner_->counters(); }

 private:
  std::unique_ptr<Device> inner_;
  DeviceRecorder& recorder_;
  const RecordingClock& clock_;
};

void check_trainee(const std::string& trainee) {
  if (trainee.empty()) throw InputError("trainer: the trainee needs a name");
  if (trainee.size() > 200) throw InputError("trainer: the trainee's name is over 200 characters");
  for (const char c : trainee) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
      throw InputError("trainer: the trainee's name contains a control character");
  }
}

void make_parent_dir(const std::filesystem::path& db) {
  if (!db.has_parent_path()) return;
  std::error_code ec;
  std::filesystem::create_directories(db.parent_path(), ec);
  if (ec) throw InputError("cannot create '" + db.parent_path().string() + "': " + ec.message());
}

}  // namespace

std::unique_ptr<Device> recording_device(std::unique_ptr<Device> inner, DeviceRecorder& recorder,
                                         const RecordingClock& clock) {
  return std::make_unique<RecordingDevice>(std::move(inner), recorder, clock);
}

std::filesystem::path trainer_records_db() {
  if (const char* env = std::getenv("PHACO_RECORDS_DB"); env && *env) return env;
  if (const char* xdg = std::getenv("XDG_DATA_HOME"); xdg && *xdg)
    return std::filesystem::path(xdg) / "openphaco" / "records.sqlite";
  if (const char* home = std::getenv("HOME"); home && *home)
    return std::filesystem::path(home) / ".local" / "share" / "openphaco" / "records.sqlite";
  throw InputError("no records database: set PHACO_RECORDS_DB");
}

void check_session_record_target(const std::filesystem::path& db, const std::string& trainee) {
  check_trainee(trainee);
  make_parent_dir(db);
  const RecordStore store(db, OpenMode::CreateIfMissing);
}

int64_t store_session_record(const std::filesystem::path& db, const std::string& trainee,
                             const Scenario& scenario, const nlohmann::json& report) {
  check_trainee(trainee);
  SessionRecord r;
  r.trainee = trainee;
  r.drill = std::string(to_string(scenario.drill));
  r.scenario_name = scenario.name.empty() ? std::filesystem::path(scenario.source).stem().string()
                                          : scenario.name;
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  const double now = static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
  double took = 0;  // the live run's length: it started that long ago
  if (report.contains("live") && report["live"].contains("wall_s") &&
      report["live"]["wall_s"].is_number())
    took = std::max(0.0, report["live"]["wall_s"].get<double>());
  r.started_utc = format_utc(now - took);
  r.finished_utc = format_utc(now);
  r.recording = to_json(scenario);
  r.settings = r.recording;
  for (const char* k : {"hands", "name", "description", "drill"}) r.settings.erase(k);
  if (report.contains("metrics") && report["metrics"].is_object()) r.metrics = report["metrics"];
  if (r.metrics.contains("score") && r.metrics["score"].is_number())
    r.score = r.metrics["score"].get<double>();
  if (report.contains("state_hash") && report["state_hash"].is_string())
    r.state_hash = report["state_hash"].get<std::string>();
  r.report = report.is_object() ? report : nlohmann::json::object();
  make_parent_dir(db);
  RecordStore store(db, OpenMode::CreateIfMissing);
  return store.add_record(r);
}

}  // namespace phaco
