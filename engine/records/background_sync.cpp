#include "engine/records/background_sync.hpp"

#include <chrono>

#include "engine/core/error.hpp"
#include "engine/records/record_location.hpp"
#include "engine/records/records.hpp"
#include "engine/records/sync.hpp"

namespace phaco {

BackgroundSync::BackgroundSync(std::filesystem::path station, std::string centre_uri,
                               double retry_s)
    : station_(std::move(station)),
      centre_(std::move(centre_uri)),
      retry_s_(retry_s),
      status_("centre " + shown_location(centre_) + ": waiting to sync") {
  worker_ = std::thread([this] { run(); });
}

BackgroundSync::~BackgroundSync() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  worker_.join();
}

void BackgroundSync::request() {
  {
    std::lock_guard lock(mutex_);
    wanted_ = true;
  }
  wake_.notify_all();
}

std::string BackgroundSync::status() const {
  std::lock_guard lock(mutex_);
  return status_;
}

int BackgroundSync::attempts() const {
  std::lock_guard lock(mutex_);
  return attempts_;
}

void BackgroundSync::run() {
  std::unique_lock lock(mutex_);
  for (;;) {
    // Wait for a request, or, while the centre fails, for the retry time.
    const auto until = std::chrono::steady_clock::now() +
                       std::chrono::milliseconds(static_cast<int64_t>(retry_s_ * 1000));
    wake_.wait_until(lock, until, [&] { return stop_ || wanted_; });
    if (stop_) return;
    if (!wanted_ && !failing_) continue;
    wanted_ = false;
    lock.unlock();
    std::string status;
    bool failed = false;
    try {
      if (!std::filesystem::exists(station_)) {
        status = "nothing recorded yet";
      } else {
        RecordStore station(station_, OpenMode::ExistingOnly);
        RecordStore centre(centre_, OpenMode::CreateIfMissing);
        const SyncResult r = sync_records(station, centre);
        status = "centre " + centre.location() + ": " + std::to_string(r.uploaded) + " uploaded, " +
                 (r.refused.empty() ? std::string("all synced")
                                    : std::to_string(r.refused.size()) + " refused");
      }
    } catch (const std::exception& e) {
      // InputError names the centre with its password masked.
      failed = true;
      status = std::string(e.what()) + " (retrying every " +
               std::to_string(static_cast<int>(retry_s_)) + " s)";
    }
    lock.lock();
    status_ = status;
    failing_ = failed;
    ++attempts_;
  }
}

}  // namespace phaco
