#pragma once
// Flat SoA element tables with tombstones, a free list and compaction with a remap table.
//
// A table is a plain struct of std::vector columns plus a `SlotIndex slots;` member and a
// `for_each_column(f)` that calls f on every column (components/ declares these). Removal only
// marks a tombstone and pushes the slot on the free list, so indices held by other tables stay
// valid during a frame; compaction (at a sync point only) closes the holes, keeps the order of
// the live elements (so results stay deterministic) and returns the old→new remap that owners
// apply to every index column that refers to this table.
#include <cassert>
#include <concepts>
#include <cstdint>
#include <span>
#include <vector>

#include "engine/core/handle.hpp"

namespace phaco {

struct Remap {
  std::vector<uint32_t> old_to_new;  // kInvalidIndex for removed elements
  uint32_t new_size = 0;

  uint32_t operator()(uint32_t old_index) const {
    return old_index < old_to_new.size() ? old_to_new[old_index] : kInvalidIndex;
  }
};

class SlotIndex {
 public:
  uint32_t size() const { return static_cast<uint32_t>(generation_.size()); }  // incl. tombstones
  uint32_t live_count() const { return size() - static_cast<uint32_t>(free_.size()); }
  bool alive(uint32_t i) const { return i < size() && alive_[i] != 0; }
  uint32_t generation(uint32_t i) const {
    assert(i < size() && "slot index past the table");
    return generation_[i];
  }
  Handle handle(uint32_t i) const { return alive(i) ? Handle{i, generation_[i]} : Handle{}; }
  bool valid(Handle h) const { return alive(h.index) && generation_[h.index] == h.generation; }
  std::span<const uint8_t> alive_mask() const { return alive_; }

  // The slot to fill next: the most recently freed one, or a new one at the end (then *appended
  // is true and the caller grows every column by one).
  uint32_t acquire(bool* appended);
  // Appends n live slots at the end, whatever the free list holds; returns the first.
  uint32_t append(uint32_t n);
  // Tombstones slot i. Removing a dead slot is a no-op that returns false.
  bool release(uint32_t i);
  // Room for n slots without reallocating (columns are reserved by their owner).
  void reserve(uint32_t n) {
    generation_.reserve(n);
    alive_.reserve(n);
  }
  // Closes the holes; generations move with their elements.
  Remap compact();
  void clear();

 private:
  std::vector<uint32_t> generation_;
  std::vector<uint8_t> alive_;
  std::vector<uint32_t> free_;  // LIFO
};

template <class T>
concept SoaTable = requires(T& t) {
  { t.slots } -> std::convertible_to<SlotIndex&>;
  t.for_each_column([](auto&) {});
};

// Debug builds: every column of a table has one entry per slot (a column left behind by an
// insertion would be read past its end, or silently shifted by the next compaction).
template <SoaTable T>
bool columns_in_step(T& table) {
  bool ok = true;
  const size_t n = table.slots.size();
  table.for_each_column([&](auto& column) { ok = ok && column.size() == n; });
  return ok;
}

// Moves the live entries of one column to their new places, in order, and shrinks it.
template <class Col>
void apply_remap(const Remap& remap, std::vector<Col>& column) {
  assert(column.size() == remap.old_to_new.size() && "a column out of step with its table");
  for (uint32_t old = 0; old < remap.old_to_new.size() && old < column.size(); ++old) {
    const uint32_t to = remap.old_to_new[old];
    if (to != kInvalidIndex && to != old) column[to] = std::move(column[old]);
  }
  column.resize(remap.new_size);
}

// Rewrites an index column that refers to a compacted table; removed targets become kInvalidIndex.
inline void remap_indices(const Remap& remap, std::span<uint32_t> indices) {
  for (uint32_t& i : indices) i = remap(i);
}

template <SoaTable T>
uint32_t table_add(T& table) {
  assert(columns_in_step(table));
  bool appended = false;
  const uint32_t i = table.slots.acquire(&appended);
  table.for_each_column([&](auto& column) {
    if (appended) {
      column.emplace_back();
    } else {
      column[i] = {};
    }
  });
  return i;
}

template <SoaTable T>
bool table_remove(T& table, uint32_t i) {
  // A dead slot is a no-op by design; an index past the table is a corrupted index column.
  assert(i < table.slots.size() && "removing an element past the table");
  return table.slots.release(i);
}

template <SoaTable T>
Remap table_compact(T& table) {
  assert(columns_in_step(table));
  Remap remap = table.slots.compact();
  table.for_each_column([&](auto& column) { apply_remap(remap, column); });
  return remap;
}

// Appends n live elements at once (bulk load of a mesh); returns the first new index.
template <SoaTable T>
uint32_t table_append(T& table, uint32_t n) {
  const uint32_t first = table.slots.append(n);
  table.for_each_column([&](auto& column) { column.resize(column.size() + n); });
  assert(columns_in_step(table));
  return first;
}

}  // namespace phaco
