#include "engine/haptics/haptic_loop.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <time.h>

#include <cerrno>
#include <fstream>
#include <stdexcept>
#include <string>
#include <system_error>

#include "engine/core/clock.hpp"
#include "engine/haptics/spin_margin.hpp"

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define PHACO_HAPTICS_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define PHACO_HAPTICS_SANITIZED 1
#endif
#endif
#ifndef PHACO_HAPTICS_SANITIZED
#define PHACO_HAPTICS_SANITIZED 0
#endif

namespace phaco {

namespace {

constexpr std::size_t kStackPrefaultBytes = 128 * 1024;  // more than a tick should ever use
constexpr int kCapIpcLock = 14;                          // linux/capability.h CAP_IPC_LOCK

inline void cpu_relax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();  // eases the spin on the sibling hyper-thread and on power
#elif defined(__aarch64__)
  asm volatile("yield");
#endif
}

// Touches the stack pages a tick may use, so the first deep call does not page-fault at 1 kHz.
[[gnu::noinline]] void prefault_stack() {
  volatile unsigned char page[kStackPrefaultBytes];
  for (std::size_t i = 0; i < kStackPrefaultBytes; i += 4096) page[i] = 0;
  (void)page;
}

// Sleeps until `target_ns` on CLOCK_MONOTONIC (absolute: an interrupted sleep resumes to the same
// instant, and wake-up latency never accumulates).
void sleep_until(int64_t target_ns) {
  timespec ts;
  ts.tv_sec = static_cast<time_t>(target_ns / 1'000'000'000);
  ts.tv_nsec = static_cast<long>(target_ns % 1'000'000'000);
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

bool has_effective_capability(int cap) {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("CapEff:", 0) == 0) {
      try {
        const unsigned long long caps = std::stoull(line.substr(7), nullptr, 16);
        return (caps >> cap) & 1ULL;
      } catch (const std::exception&) {
        return false;  // unreadable: assume the capability is missing
      }
    }
  }
  return false;
}

void append(std::string& detail, const std::string& what) {
  if (!detail.empty()) detail += "; ";
  detail += what;
}

}  // namespace

HapticLoop::~HapticLoop() {
  stop();
}

void HapticLoop::start(TickFn tick, void* context, const LoopSettings& settings) {
  if (thread_.joinable()) throw std::logic_error("HapticLoop::start: already running");
  if (tick == nullptr) throw std::invalid_argument("HapticLoop::start: no tick function");
  if (settings.period_ns <= 0)
    throw std::invalid_argument("HapticLoop::start: period_ns must be > 0");
  if (settings.spin_ns < 0) throw std::invalid_argument("HapticLoop::start: spin_ns must be >= 0");
  if (settings.max_spin_ns < 0)
    throw std::invalid_argument("HapticLoop::start: max_spin_ns must be >= 0");
  if (settings.start_margin_ns < 0)
    throw std::invalid_argument("HapticLoop::start: start_margin_ns must be >= 0");
  if (settings.warmup_ticks < 0)
    throw std::invalid_argument("HapticLoop::start: warmup_ticks must be >= 0");
  if (settings.realtime && (settings.priority < 1 || settings.priority > 99))
    throw std::invalid_argument("HapticLoop::start: SCHED_FIFO priority must be 1-99");

  tick_ = tick;
  context_ = context;
  settings_ = settings;
  status_ = RealtimeStatus{};
  start_ns_ = 0;
  stats_.reset();
  // Relaxed: the thread does not exist yet; its creation orders these stores before its start.
  stop_.store(false, std::memory_order_relaxed);
  ready_.store(false, std::memory_order_relaxed);
  thread_ = std::thread([this] { run(); });
  // Acquire: pairs with the thread's release, so status_ and start_ns_ are visible from here on.
  ready_.wait(false, std::memory_order_acquire);
}

void HapticLoop::stop() {
  if (!thread_.joinable()) return;
  // Relaxed: a request only; the join below is what synchronises with the thread's last tick.
  stop_.store(true, std::memory_order_relaxed);
  thread_.join();
}

void HapticLoop::set_up_thread() {
  RealtimeStatus& s = status_;
  s.requested = settings_.realtime;
  const pthread_t self = pthread_self();

  if (settings_.cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(settings_.cpu, &set);
    const int rc = pthread_setaffinity_np(self, sizeof(set), &set);
    s.pinned = rc == 0;
    if (rc != 0)
      append(s.detail, "pinning to CPU " + std::to_string(settings_.cpu) +
                           " refused: " + std::generic_category().message(rc));
  }

  if (settings_.realtime) {
    sched_param param{};
    param.sched_priority = settings_.priority;
    const int rc = pthread_setschedparam(self, SCHED_FIFO, &param);
    if (rc != 0)
      append(s.detail, "SCHED_FIFO refused: " + std::generic_category().message(rc) +
                           " (need CAP_SYS_NICE or an rtprio limit >= " +
                           std::to_string(settings_.priority) + ")");
  } else {
    append(s.detail, "real-time priority not requested");
  }
  // Read back what the thread actually runs under: never report what was merely asked for.
  int policy = 0;
  sched_param got{};
  if (pthread_getschedparam(self, &policy, &got) == 0) {
    s.fifo = policy == SCHED_FIFO;
    s.priority = got.sched_priority;
  }

  if (settings_.lock_memory) {
    rlimit limit{};
    getrlimit(RLIMIT_MEMLOCK, &limit);
    const bool unlimited = limit.rlim_cur == RLIM_INFINITY || has_effective_capability(kCapIpcLock);
    if (PHACO_HAPTICS_SANITIZED) {
      // A sanitizer maps terabytes of shadow memory: locking it all would never finish.
      append(s.detail, "memory not locked: sanitizer build");
    } else if (!unlimited) {
      // MCL_FUTURE under a finite limit makes the simulation's later allocations fail once the
      // limit is reached: better unlocked than out of memory.
      append(s.detail, "memory not locked: RLIMIT_MEMLOCK is " +
                           std::to_string(limit.rlim_cur / 1024) +
                           " KiB and no CAP_IPC_LOCK (locking future allocations would fail them)");
    } else if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
      append(s.detail, "mlockall refused: " + std::generic_category().message(errno));
    } else {
      s.memory_locked = true;
    }
  }

  // The kernel may defer a normal thread's timer wake-up by its timer slack (50 µs by default)
  // to batch wake-ups; 1 ns asks for none. SCHED_FIFO threads have no slack anyway.
  if (prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL) != 0)
    append(s.detail, "timer slack not reduced: " + std::generic_category().message(errno));

  prefault_stack();
}

void HapticLoop::run() {
  set_up_thread();
  const int64_t period = settings_.period_ns;
  // spin_ns = 0 sleeps only, whatever max_spin_ns says; ≥ period spins only.
  SpinMargin margin{.floor_ns = settings_.spin_ns,
                    .cap_ns = settings_.spin_ns == 0 ? 0 : settings_.max_spin_ns};
  if (settings_.start_margin_ns > 0) margin.start_at(settings_.start_margin_ns);
  // Relaxed: a figure; start() returns after the release below, so it reads this one.
  spin_margin_ns_.store(margin.margin_ns(), std::memory_order_relaxed);
  const int64_t warmup = settings_.warmup_ticks;
  // One period of margin before the first deadline, so tick 0 is not late by construction.
  start_ns_ = now_ns() + period;
  // Release: status_ and start_ns_ are complete before start() returns to its caller.
  ready_.store(true, std::memory_order_release);
  ready_.notify_one();

  int64_t k = 0;
  int64_t ticks_run = 0;
  int64_t previous_wake = -1;
  // Relaxed: the flag carries no data; stop() joins the thread afterwards.
  while (!stop_.load(std::memory_order_relaxed)) {
    const int64_t deadline = start_ns_ + k * period;
    if (const int64_t m = margin.margin_ns(); m < period) {
      const int64_t sleep_target = deadline - m;
      if (now_ns() < sleep_target) {
        sleep_until(sleep_target);
        margin.observe_sleep(now_ns() - sleep_target);
      }
    }
    int64_t wake = now_ns();
    const int64_t spin_from = wake;
    while (wake < deadline) {
      cpu_relax();
      wake = now_ns();
    }
    margin.decay();

    tick_(context_, TickInfo{k, deadline, wake});
    const int64_t end = now_ns();

    // Deadlines after this one that had already passed when the tick began.
    const int64_t missed = (wake - deadline) / period;
    if (ticks_run >= warmup) {
      stats_.record_tick(previous_wake >= 0 ? wake - previous_wake : -1, wake - deadline,
                         end - wake, wake - spin_from);
      if (missed > 0) stats_.record_overrun(missed);
    }
    // Relaxed: a figure for the owner (the next loop's start_margin_ns), no synchronisation.
    spin_margin_ns_.store(margin.margin_ns(), std::memory_order_relaxed);
    previous_wake = wake;
    ++ticks_run;
    k += 1 + missed;  // the next deadline still in the future at wake-up
  }
}

}  // namespace phaco
