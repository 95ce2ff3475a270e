#include "perf/cores.hpp"

#include <pthread.h>

#include <algorithm>
#include <chrono>
#include <limits>
#include <vector>

namespace phaco::perf {

std::pair<int, int> two_cpus() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (pthread_getaffinity_np(pthread_self(), sizeof(set), &set) != 0 || CPU_COUNT(&set) < 2)
    return {-1, -1};
  int low = -1, high = -1;
  for (int c = 0; c < CPU_SETSIZE; ++c) {
    if (!CPU_ISSET(c, &set)) continue;
    if (low < 0) low = c;
    high = c;
  }
  return {low, high};
}

PinnedScope::PinnedScope(int cpu) {
  if (cpu < 0) return;
  ok_ = pthread_getaffinity_np(pthread_self(), sizeof old_, &old_) == 0;
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  ok_ = ok_ && pthread_setaffinity_np(pthread_self(), sizeof set, &set) == 0;
}

PinnedScope::~PinnedScope() {
  if (ok_) pthread_setaffinity_np(pthread_self(), sizeof old_, &old_);
}

RoundTripPartner::RoundTripPartner(int cpu) {
  partner_ = std::thread([this, cpu] {
    const PinnedScope pin(cpu);
    for (int64_t seen = 1;; seen += 2) {
      while (ball_.load(std::memory_order_acquire) != seen)
        if (done_.load(std::memory_order_relaxed)) return;
      ball_.store(seen + 1, std::memory_order_release);
    }
  });
}

RoundTripPartner::~RoundTripPartner() {
  done_.store(true, std::memory_order_relaxed);
  partner_.join();
}

double core_round_trip_ns(int batches, int trips) {
  const auto [first, last] = two_cpus();
  if (first < 0 || batches < 1 || trips < 1) return std::numeric_limits<double>::quiet_NaN();
  const PinnedScope pin(first);
  RoundTripPartner partner(last);
  partner.trip();  // the partner is up and the line is in play before the clock starts
  std::vector<double> per_trip;
  for (int b = 0; b < batches; ++b) {
    const auto t0 = std::chrono::steady_clock::now();
    for (int k = 0; k < trips; ++k) partner.trip();
    const std::chrono::duration<double, std::nano> took = std::chrono::steady_clock::now() - t0;
    per_trip.push_back(took.count() / trips);
  }
  std::nth_element(per_trip.begin(), per_trip.begin() + batches / 2, per_trip.end());
  return per_trip[batches / 2];
}

}  // namespace phaco::perf
