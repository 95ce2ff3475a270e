#include "engine/core/table.hpp"

#include <cassert>

namespace phaco {

uint32_t SlotIndex::acquire(bool* appended) {
  // Reusing the most recently freed slot keeps the table dense between compactions.
  if (!free_.empty()) {
    const uint32_t i = free_.back();
    free_.pop_back();
    assert(i < size() && !alive_[i] && "a live or missing slot on the free list");
    alive_[i] = 1;
    *appended = false;
    return i;
  }
  generation_.push_back(0);
  alive_.push_back(1);
  *appended = true;
  return size() - 1;
}

uint32_t SlotIndex::append(uint32_t n) {
  const uint32_t first = size();
  assert(n < kInvalidIndex - first && "the table would reach the invalid index");
  generation_.resize(first + n, 0);
  alive_.resize(first + n, 1);
  return first;
}

bool SlotIndex::release(uint32_t i) {
  if (!alive(i)) return false;
  alive_[i] = 0;
  // A wrapped generation would make handles from 2^32 removals ago valid again.
  assert(generation_[i] != UINT32_MAX && "slot generation wrapped");
  ++generation_[i];  // stale handles to this slot stop validating
  free_.push_back(i);
  return true;
}

Remap SlotIndex::compact() {
  Remap remap;
  remap.old_to_new.assign(size(), kInvalidIndex);
  uint32_t next = 0;
  for (uint32_t i = 0; i < size(); ++i) {
    if (!alive_[i]) continue;
    remap.old_to_new[i] = next;
    generation_[next] = generation_[i];
    alive_[next] = 1;
    ++next;
  }
  remap.new_size = next;
  assert(next == live_count() && "the free list and the alive mask disagree");
  generation_.resize(next);
  alive_.resize(next);
  free_.clear();
  return remap;
}

void SlotIndex::clear() {
  generation_.clear();
  alive_.clear();
  free_.clear();
}

}  // namespace phaco
