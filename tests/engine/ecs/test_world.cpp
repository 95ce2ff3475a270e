#include <gtest/gtest.h>

#include "engine/ecs/world.hpp"

namespace phaco {
namespace {

struct Mass {
  float kg = 0;
};
struct Label {
  std::string text;
};

TEST(World, CreateFindDestroy) {
  World w;
  const Entity capsule = w.create(EntityKind::Body, "capsule");
  const Entity forceps = w.create(EntityKind::Tool, "forceps");
  EXPECT_EQ(w.entity_count(), 2u);
  EXPECT_EQ(w.kind(forceps), EntityKind::Tool);
  EXPECT_EQ(w.name(capsule), "capsule");
  ASSERT_TRUE(w.find("forceps").has_value());
  EXPECT_EQ(*w.find("forceps"), forceps);
  EXPECT_FALSE(w.find("hook").has_value());
  EXPECT_TRUE(w.destroy(capsule));
  EXPECT_FALSE(w.destroy(capsule));
  EXPECT_FALSE(w.alive(capsule));
  EXPECT_EQ(w.entity_count(), 1u);
  EXPECT_THROW(w.name(capsule), std::logic_error);
}

TEST(World, ComponentsAddGetRemove) {
  World w;
  const Entity a = w.create(EntityKind::Body, "a");
  const Entity b = w.create(EntityKind::Body, "b");
  w.add(a, Mass{2.0f});
  w.add(b, Label{"lens"});
  ASSERT_NE(w.get<Mass>(a), nullptr);
  EXPECT_FLOAT_EQ(w.get<Mass>(a)->kg, 2.0f);
  EXPECT_EQ(w.get<Mass>(b), nullptr);
  EXPECT_TRUE(w.has<Label>(b));
  EXPECT_TRUE(w.remove<Label>(b));
  EXPECT_FALSE(w.has<Label>(b));
  EXPECT_THROW(w.at<Label>(b), std::logic_error);
}

TEST(World, StaleHandleSeesNothingAfterSlotReuse) {
  World w;
  const Entity old = w.create(EntityKind::Tool, "keratome");
  w.add(old, Mass{1.0f});
  w.destroy(old);
  const Entity fresh = w.create(EntityKind::Tool, "hook");
  ASSERT_EQ(fresh.index, old.index) << "slot reused";
  EXPECT_NE(fresh.generation, old.generation);
  EXPECT_EQ(w.get<Mass>(old), nullptr);
  EXPECT_EQ(w.get<Mass>(fresh), nullptr) << "components of the destroyed entity do not leak";
  EXPECT_FALSE(w.alive(old));
}

TEST(World, EachVisitsInEntityOrder) {
  World w;
  std::vector<Entity> made;
  for (int i = 0; i < 5; ++i) made.push_back(w.create(EntityKind::Body, "b" + std::to_string(i)));
  for (int i = 4; i >= 0; --i) w.add(made[i], Mass{float(i)});
  w.destroy(made[2]);
  std::vector<float> seen;
  w.each<Mass>([&](Entity, Mass& m) { seen.push_back(m.kg); });
  EXPECT_EQ((std::vector<float>{0, 1, 3, 4}), seen);
}

}  // namespace
}  // namespace phaco
