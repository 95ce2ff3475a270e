#include <gtest/gtest.h>

#include <string>

#include "engine/schedule/access_check.hpp"

namespace phaco {
namespace {

SystemDesc sys(std::string name, std::vector<std::string> reads, std::vector<std::string> writes) {
  SystemDesc s;
  s.name = std::move(name);
  s.reads = std::move(reads);
  s.writes = std::move(writes);
  s.run = [](const FrameContext&) {};
  return s;
}

// All in one phase, registration order = graph order: cut 0, tear 1, render 2, haptics 3,
// integrate 4.
FrameGraph make_graph() {
  return FrameGraph({sys("cut", {}, {"capsule.triangles"}), sys("tear", {}, {"capsule.triangles"}),
                     sys("render", {"capsule.triangles"}, {}),
                     sys("haptics", {"capsule.triangles"}, {"haptic.model"}),
                     sys("integrate", {"capsule.x"}, {"capsule.x"})});
}

TEST(AccessTracker, RefusesSecondWriterAndNamesBoth) {
  const FrameGraph g = make_graph();
  AccessTracker tracker(g);
  ASSERT_FALSE(tracker.try_enter(0));
  const auto conflict = tracker.try_enter(1);
  ASSERT_TRUE(conflict);
  EXPECT_EQ(conflict->running, 0u);
  EXPECT_EQ(conflict->starting, 1u);
  EXPECT_TRUE(conflict->both_write);
  EXPECT_EQ(g.components()[conflict->component], "capsule.triangles");
  const std::string text = tracker.describe(*conflict);
  EXPECT_NE(text.find("'cut'"), std::string::npos) << text;
  EXPECT_NE(text.find("'tear'"), std::string::npos) << text;
  EXPECT_NE(text.find("capsule.triangles"), std::string::npos) << text;
  tracker.exit(0);
  EXPECT_FALSE(tracker.try_enter(1));  // sequential writers are fine
}

TEST(AccessTracker, RefusesReadWhileWriteInBothOrders) {
  const FrameGraph g = make_graph();
  AccessTracker tracker(g);
  ASSERT_FALSE(tracker.try_enter(0));  // cut writes
  auto reader = tracker.try_enter(2);  // render reads
  ASSERT_TRUE(reader);
  EXPECT_FALSE(reader->both_write);
  EXPECT_EQ(reader->running, 0u);
  tracker.exit(0);

  ASSERT_FALSE(tracker.try_enter(2));  // two readers together are fine
  ASSERT_FALSE(tracker.try_enter(3));
  auto writer = tracker.try_enter(1);  // tear would write under them
  ASSERT_TRUE(writer);
  EXPECT_FALSE(writer->both_write);
  EXPECT_TRUE(writer->running == 2u || writer->running == 3u);
  EXPECT_EQ(writer->starting, 1u);
}

TEST(AccessTracker, OwnReadWriteAndDisjointSystemsPass) {
  const FrameGraph g = make_graph();
  AccessTracker tracker(g);
  EXPECT_FALSE(tracker.try_enter(4));  // integrate reads and writes capsule.x itself
  EXPECT_FALSE(tracker.try_enter(0));  // disjoint from integrate
  tracker.exit(4);
  tracker.exit(0);
  ASSERT_FALSE(tracker.try_enter(0));
  tracker.clear();  // forgets cut, as after an aborted frame
  EXPECT_FALSE(tracker.try_enter(1));
}

TEST(AccessTrackerDeathTest, EnterAbortsNamingBothSystems) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  const FrameGraph g = make_graph();
  AccessTracker tracker(g);
  tracker.enter(0);
  EXPECT_DEATH(tracker.enter(1), "'tear' started while 'cut' was running");
}

}  // namespace
}  // namespace phaco
