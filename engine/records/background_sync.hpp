#pragma once
// The trainer's sync to a centre in the background (issue 21 item 2): a station records each
// drill to its own file first (the trainee never waits on the network), and this worker uploads
// to the centre when asked and, while the centre is unreachable, tries again every `retry_s`.
//
// Thread-safety: request() and status() may be called from any thread; the worker thread is the
// only one that opens the databases. The destructor asks the worker to stop and joins it: a sync
// in progress finishes its batch or its connection attempt first (at most kConnectTimeoutS), and
// whatever it did not send is sent by the next sync (sync.hpp), so nothing is lost by quitting.
#include <condition_variable>
#include <filesystem>
#include <mutex>
#include <string>
#include <thread>

namespace phaco {

class BackgroundSync {
 public:
  // Starts the worker. Thread: the owner, as the destructor (which joins the worker).
  BackgroundSync(std::filesystem::path station, std::string centre_uri, double retry_s = 30.0);
  ~BackgroundSync();
  BackgroundSync(const BackgroundSync&) = delete;
  BackgroundSync& operator=(const BackgroundSync&) = delete;

  // Asks for a sync as soon as the worker is free (a new record was stored). Thread: any.
  void request();
  // One line for the trainer's panel: "centre: 12 uploaded (all synced)", "centre unreachable
  // (retrying in 30 s): …", never the password. Thread: any.
  std::string status() const;
  // Syncs finished (successful or not), for tests. Thread: any.
  int attempts() const;

 private:
  void run();

  const std::filesystem::path station_;
  const std::string centre_;
  const double retry_s_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  bool wanted_ = true, stop_ = false, failing_ = false;
  int attempts_ = 0;
  std::string status_;
  std::thread worker_;
};

}  // namespace phaco
