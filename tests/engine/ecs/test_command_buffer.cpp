#include <gtest/gtest.h>

#include "engine/ecs/command_buffer.hpp"

namespace phaco {
namespace {

struct Particles {
  SlotIndex slots;
  std::vector<float> x;  // mm
  template <class F>
  void for_each_column(F&& f) {
    f(x);
  }
};
struct Tag {
  int value = 0;
};
struct Code {
  uint64_t value = 0;
};

TEST(CommandBuffer, NothingChangesUntilApply) {
  World w;
  const Entity body = w.create(EntityKind::Body, "capsule");
  Particles p;
  table_append(p, 4);
  w.add(body, std::move(p));
  CommandQueues q(2);
  q.for_worker(1).remove_element<Particles>(3, body, 3);
  q.for_worker(0).add(1, body, Tag{5});
  q.for_worker(0).create(2, EntityKind::Tool, "forceps");
  EXPECT_EQ(q.pending(), 3u);
  EXPECT_FALSE(w.has<Tag>(body));
  EXPECT_TRUE(w.at<Particles>(body).slots.alive(3));
  EXPECT_EQ(q.apply(w), 3u);
  EXPECT_EQ(q.pending(), 0u);
  EXPECT_EQ(w.at<Tag>(body).value, 5);
  EXPECT_FALSE(w.at<Particles>(body).slots.alive(3));
  EXPECT_TRUE(w.find("forceps").has_value());
}

// The order of application depends on keys only, not on which worker recorded a command.
TEST(CommandBuffer, ApplyOrderIndependentOfWorkers) {
  auto run = [](int workers) {
    World w;
    const Entity e = w.create(EntityKind::Body, "lens");
    w.add(e, Code{0});
    CommandQueues q(workers);
    for (uint64_t key = 0; key < 20; ++key) {
      const int worker = static_cast<int>((key * 7) % static_cast<uint64_t>(workers));
      // Non-commutative update: the final value encodes the order.
      q.for_worker(worker).push(19 - key, [e, key](World& world) {
        world.at<Code>(e).value = world.at<Code>(e).value * 3 + key % 5;  // wraps modulo 2^64
      });
    }
    q.apply(w);
    return w.at<Code>(e).value;
  };
  const uint64_t one = run(1);
  EXPECT_EQ(one, run(2));
  EXPECT_EQ(one, run(4));
}

TEST(CommandBuffer, CommandsOnDestroyedEntityAreSkipped) {
  World w;
  const Entity e = w.create(EntityKind::Body, "iris");
  CommandQueues q(1);
  q.for_worker(0).destroy(0, e);
  q.for_worker(0).add(1, e, Tag{1});
  q.for_worker(0).remove_element<Particles>(2, e, 0);
  EXPECT_EQ(q.apply(w), 3u);
  EXPECT_FALSE(w.alive(e));
  EXPECT_EQ(w.entity_count(), 0u);
}

}  // namespace
}  // namespace phaco
