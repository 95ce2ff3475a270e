#include <gtest/gtest.h>

#include "engine/core/table.hpp"

namespace phaco {
namespace {

struct Points {
  SlotIndex slots;
  std::vector<float> x;       // mm
  std::vector<uint32_t> tag;  // a payload that identifies the original element
  template <class F>
  void for_each_column(F&& f) {
    f(x);
    f(tag);
  }
};

Points make_points(uint32_t n) {
  Points p;
  for (uint32_t k = 0; k < n; ++k) {
    const uint32_t i = table_add(p);
    p.x[i] = static_cast<float>(k) * 0.5f;
    p.tag[i] = k;
  }
  return p;
}

TEST(Table, AddGrowsEveryColumn) {
  Points p = make_points(5);
  EXPECT_EQ(p.slots.size(), 5u);
  EXPECT_EQ(p.slots.live_count(), 5u);
  EXPECT_EQ(p.x.size(), 5u);
  EXPECT_EQ(p.tag.size(), 5u);
  EXPECT_FLOAT_EQ(p.x[4], 2.0f);
}

TEST(Table, RemoveLeavesTombstoneAndReusesSlot) {
  Points p = make_points(5);
  EXPECT_TRUE(table_remove(p, 2));
  EXPECT_FALSE(table_remove(p, 2)) << "removing a dead slot twice must be a no-op";
  EXPECT_FALSE(p.slots.alive(2));
  EXPECT_EQ(p.slots.size(), 5u) << "indices held elsewhere stay valid until compaction";
  EXPECT_EQ(p.slots.live_count(), 4u);
  const uint32_t reused = table_add(p);
  EXPECT_EQ(reused, 2u);
  EXPECT_EQ(p.tag[reused], 0u) << "a reused slot starts value-initialised";
  EXPECT_EQ(p.x.size(), 5u);
}

TEST(Table, CompactKeepsOrderAndReturnsRemap) {
  Points p = make_points(6);
  table_remove(p, 0);
  table_remove(p, 3);
  table_remove(p, 5);
  const Remap r = table_compact(p);
  ASSERT_EQ(r.new_size, 3u);
  EXPECT_EQ(p.slots.size(), 3u);
  EXPECT_EQ(p.x.size(), 3u);
  EXPECT_EQ((std::vector<uint32_t>{1, 2, 4}), p.tag);
  EXPECT_EQ(r(0), kInvalidIndex);
  EXPECT_EQ(r(1), 0u);
  EXPECT_EQ(r(2), 1u);
  EXPECT_EQ(r(3), kInvalidIndex);
  EXPECT_EQ(r(4), 2u);
  EXPECT_EQ(r(99), kInvalidIndex);
  // After compaction there is no free slot: the next add appends.
  EXPECT_EQ(table_add(p), 3u);
}

TEST(Table, RemapRewritesReferencingIndexColumns) {
  Points p = make_points(4);
  std::vector<uint32_t> springs_i = {0, 1, 2, 3, 3};
  table_remove(p, 1);
  const Remap r = table_compact(p);
  remap_indices(r, springs_i);
  EXPECT_EQ((std::vector<uint32_t>{0, kInvalidIndex, 1, 2, 2}), springs_i);
}

TEST(Table, BulkAppendIgnoresFreeList) {
  Points p = make_points(3);
  table_remove(p, 1);
  const uint32_t first = table_append(p, 4);
  EXPECT_EQ(first, 3u);
  EXPECT_EQ(p.slots.size(), 7u);
  EXPECT_EQ(p.x.size(), 7u);
  EXPECT_FALSE(p.slots.alive(1));
  EXPECT_TRUE(p.slots.alive(6));
}

TEST(Handle, StaleHandleIsDetected) {
  Points p = make_points(3);
  const Handle h = p.slots.handle(1);
  EXPECT_TRUE(p.slots.valid(h));
  table_remove(p, 1);
  EXPECT_FALSE(p.slots.valid(h)) << "handle to a removed element";
  const uint32_t again = table_add(p);
  ASSERT_EQ(again, 1u);
  EXPECT_FALSE(p.slots.valid(h)) << "slot reused: the old handle's generation is stale";
  EXPECT_TRUE(p.slots.valid(p.slots.handle(1)));
  EXPECT_TRUE(p.slots.handle(99).is_null());
}

TEST(Handle, GenerationFollowsElementThroughCompaction) {
  Points p = make_points(3);
  table_remove(p, 0);
  table_add(p);  // slot 0 reused, generation 1
  table_remove(p, 1);
  const uint32_t gen_of_2 = p.slots.generation(2);
  table_compact(p);
  EXPECT_EQ(p.slots.generation(0), 1u);
  EXPECT_EQ(p.slots.generation(1), gen_of_2);
}

}  // namespace
}  // namespace phaco
