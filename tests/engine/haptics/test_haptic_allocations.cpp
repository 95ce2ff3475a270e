// The haptic path allocates nothing after start-up (issue 6 item 2): a 1 kHz loop whose tick
// acquires the newest HapticModel from a triple buffer and pushes a device sample into an SPSC
// ring, while the test thread publishes models and drains samples, as the simulation would.
// Only allocations made on the haptic thread count (tests/engine/haptics/alloc_counter.hpp).
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <thread>
#include <vector>

#include "components/haptic_model.hpp"
#include "engine/core/clock.hpp"
#include "engine/haptics/haptic_loop.hpp"
#include "engine/haptics/spsc_ring.hpp"
#include "engine/haptics/triple_buffer.hpp"
#include "tests/engine/haptics/alloc_counter.hpp"

namespace phaco {
namespace {

struct Sample {
  int64_t tick = 0;
  uint64_t model_sequence = 0;
  float force_mn = 0;
};

struct HapticSide {
  TripleBuffer<HapticModel>* models = nullptr;
  SpscRing<Sample, 256>* samples = nullptr;
  bool marked = false;         // loop thread only
  uint64_t last_sequence = 0;  // loop thread only
  std::atomic<int64_t> acquired{0};
  std::atomic<int64_t> sequence_went_back{0};

  static void tick(void* self, const TickInfo& info) {
    auto* h = static_cast<HapticSide*>(self);
    if (!h->marked) {  // start-up is over: from here every allocation on this thread counts
      test::count_allocations_on_this_thread(true);
      h->marked = true;
    }
    // Relaxed counters: statistics read after the join.
    if (h->models->acquire()) {
      h->acquired.store(h->acquired.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
      const uint64_t seq = h->models->read_slot().sequence;
      if (seq < h->last_sequence) h->sequence_went_back.store(1, std::memory_order_relaxed);
      h->last_sequence = seq;
    }
    const HapticTool& tool = h->models->read_slot().tools[0];
    float f = 0;  // a token force: a few springs' worth of reading the model
    for (uint32_t i = 0; i < tool.node_count && i < 64; ++i) f += tool.x[i] * tool.mass[i];
    h->samples->try_push(Sample{info.index, h->last_sequence, f});
  }
};

TEST(HapticAllocations, CounterSeesAnAllocationOnAMarkedThread) {
  if (!test::haptic_allocation_counting_available())
    GTEST_SKIP() << "operator new is the sanitizer's own in this build; counting is off";
  test::count_allocations_on_this_thread(true);
  test::open_allocation_window();
  volatile std::size_t n = 100;
  auto block = std::make_unique<std::vector<int>>(n);
  test::close_allocation_window();
  test::count_allocations_on_this_thread(false);
  EXPECT_EQ(block->size(), 100u);
  EXPECT_GE(test::allocations_on_marked_threads(), 2);  // the vector object and its storage
}

struct HandoffResult {
  long haptic_allocations = 0;  // on the haptic thread, after its first tick
  int64_t ticks = 0;
  int64_t acquired = 0;  // models the haptic thread took
  int64_t drained = 0;   // samples the simulation side received
  uint64_t dropped = 0;
  bool model_sequence_went_back = false;
  bool samples_out_of_order = false;
  bool fifo = false;
};

// Runs the loop with the handoff for at least 0.3 s and until the path has been exercised (a
// loaded machine may tick slowly; 10 s at most). The test thread plays the simulation: it publishes
// a model every ~3 ms, drains the samples each "frame", and allocates freely (not counted: it is
// not marked).
HandoffResult run_handoff() {
  auto models = std::make_unique<TripleBuffer<HapticModel>>();
  auto samples = std::make_unique<SpscRing<Sample, 256>>();
  HapticSide side;
  side.models = models.get();
  side.samples = samples.get();

  LoopSettings settings;
  settings.lock_memory = false;  // MCL_FUTURE would stay on for the rest of the test binary
  settings.warmup_ticks = 10;
  HapticLoop loop;
  HandoffResult result;
  test::open_allocation_window();
  loop.start(&HapticSide::tick, &side, settings);

  uint64_t sequence = 0;
  int64_t last_tick = -1;
  uint64_t last_sequence = 0;
  auto receive = [&](const Sample& s) {
    result.samples_out_of_order |= s.tick <= last_tick;
    result.model_sequence_went_back |= s.model_sequence < last_sequence;
    last_tick = s.tick;
    last_sequence = s.model_sequence;
  };
  const int64_t t0 = now_ns();
  while (now_ns() < t0 + 300'000'000 || ((result.drained <= 100 || side.acquired.load() <= 10) &&
                                         now_ns() < t0 + 10'000'000'000)) {
    result.drained += static_cast<int64_t>(samples->drain(receive));
    HapticModel& m = models->write_slot();
    m.sequence = ++sequence;
    m.tools[0].present = true;
    m.tools[0].node_count = 64;
    for (uint32_t i = 0; i < 64; ++i) {
      m.tools[0].x[i] = static_cast<float>(sequence + i);
      m.tools[0].mass[i] = 1e-6f;
    }
    models->publish();
    std::vector<double> scratch(1000, 1.0);  // the simulation may allocate
    std::this_thread::sleep_for(std::chrono::milliseconds(3));
  }
  test::close_allocation_window();
  loop.stop();
  result.drained += static_cast<int64_t>(samples->drain(receive));

  result.haptic_allocations = test::allocations_on_marked_threads();
  result.ticks = loop.stats().ticks;
  result.acquired = side.acquired.load();
  result.dropped = samples->dropped();
  result.model_sequence_went_back |= side.sequence_went_back.load() != 0;
  result.fifo = loop.realtime_status().fifo;
  std::printf("ticks %lld, models acquired %lld, samples drained %lld, dropped %llu, fifo %d\n",
              static_cast<long long>(result.ticks), static_cast<long long>(result.acquired),
              static_cast<long long>(result.drained),
              static_cast<unsigned long long>(result.dropped), result.fifo);
  return result;
}

// Also the ThreadSanitizer check of the whole haptic path: runs in every build.
TEST(HapticHandoff, ModelsArriveNewestFirstAndSamplesInOrder) {
  const HandoffResult r = run_handoff();
  EXPECT_GT(r.acquired, 10);
  EXPECT_GT(r.drained, 100);
  EXPECT_FALSE(r.model_sequence_went_back);
  EXPECT_FALSE(r.samples_out_of_order);
}

TEST(HapticAllocations, LoopWithHandoffAllocatesNothingOnTheHapticThread) {
  if (!test::haptic_allocation_counting_available())
    GTEST_SKIP() << "operator new is the sanitizer's own in this build; counting is off";
  const HandoffResult r = run_handoff();
  EXPECT_EQ(r.haptic_allocations, 0);
  EXPECT_GT(r.acquired, 10);  // the path was really exercised
  EXPECT_GT(r.drained, 100);
}

}  // namespace
}  // namespace phaco
