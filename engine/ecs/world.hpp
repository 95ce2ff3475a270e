#pragma once
// The World: bodies and tools as entities (generational handles) with their components.
//
// Entities are few (a handful of bodies and tools); their elements (particles, springs, tets...)
// live in flat SoA tables inside components, so per-entity lookups here are never on a hot path.
// Component storage is one pool per type: entity index -> component, iterated in entity-index
// order so that every walk over the world is deterministic.
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "engine/core/handle.hpp"
#include "engine/core/table.hpp"

namespace phaco {

using Entity = Handle;

enum class EntityKind : uint8_t { Body, Tool };

namespace detail {
uint32_t next_component_type_id();
template <class C>
uint32_t component_type_id() {
  static const uint32_t id = next_component_type_id();
  return id;
}

struct PoolBase {
  virtual ~PoolBase() = default;
  virtual bool erase(uint32_t entity_index) = 0;
};

template <class C>
struct Pool final : PoolBase {
  std::vector<std::optional<C>> by_entity;  // indexed by entity index
  bool erase(uint32_t entity_index) override {
    if (entity_index >= by_entity.size() || !by_entity[entity_index]) return false;
    by_entity[entity_index].reset();
    return true;
  }
};
}  // namespace detail

class World {
 public:
  Entity create(EntityKind kind, std::string name);
  // Removes the entity and all its components; false if it was already gone (stale handle).
  bool destroy(Entity e);
  bool alive(Entity e) const { return entities_.slots.valid(e); }
  EntityKind kind(Entity e) const { return entities_.kind[checked(e)]; }
  const std::string& name(Entity e) const { return entities_.name[checked(e)]; }
  std::optional<Entity> find(std::string_view name) const;
  // Live entities in index order.
  std::vector<Entity> entities() const;
  uint32_t entity_count() const { return entities_.slots.live_count(); }

  template <class C>
  C& add(Entity e, C component) {
    auto& pool = pool_for<C>();
    const uint32_t i = checked(e);
    if (pool.by_entity.size() <= i) pool.by_entity.resize(i + 1);
    pool.by_entity[i] = std::move(component);
    return *pool.by_entity[i];
  }
  template <class C>
  C* get(Entity e) {
    auto* pool = find_pool<C>();
    if (!pool || !alive(e) || e.index >= pool->by_entity.size() || !pool->by_entity[e.index]) {
      return nullptr;
    }
    return &*pool->by_entity[e.index];
  }
  template <class C>
  const C* get(Entity e) const {
    return const_cast<World*>(this)->get<C>(e);
  }
  // Like get, but a missing component is a programming error.
  template <class C>
  C& at(Entity e) {
    C* c = get<C>(e);
    if (!c) throw std::logic_error("entity '" + name(e) + "' has no such component");
    return *c;
  }
  template <class C>
  bool has(Entity e) const {
    return get<C>(e) != nullptr;
  }
  template <class C>
  bool remove(Entity e) {
    auto* pool = find_pool<C>();
    return pool && alive(e) && pool->erase(e.index);
  }
  // f(Entity, C&) for every live entity that has C, in entity-index order.
  template <class C, class F>
  void each(F&& f) {
    auto* pool = find_pool<C>();
    if (!pool) return;
    for (uint32_t i = 0; i < pool->by_entity.size(); ++i) {
      if (pool->by_entity[i] && entities_.slots.alive(i)) f(entities_.slots.handle(i), *pool->by_entity[i]);
    }
  }

 private:
  struct EntityTable {
    SlotIndex slots;
    std::vector<EntityKind> kind;
    std::vector<std::string> name;
    template <class F>
    void for_each_column(F&& f) {
      f(kind);
      f(name);
    }
  };

  uint32_t checked(Entity e) const {
    if (!alive(e)) throw std::logic_error("stale or null entity handle");
    return e.index;
  }
  template <class C>
  detail::Pool<C>* find_pool() {
    const uint32_t id = detail::component_type_id<C>();
    return id < pools_.size() ? static_cast<detail::Pool<C>*>(pools_[id].get()) : nullptr;
  }
  template <class C>
  detail::Pool<C>& pool_for() {
    const uint32_t id = detail::component_type_id<C>();
    if (pools_.size() <= id) pools_.resize(id + 1);
    if (!pools_[id]) pools_[id] = std::make_unique<detail::Pool<C>>();
    return static_cast<detail::Pool<C>&>(*pools_[id]);
  }

  EntityTable entities_;
  std::vector<std::unique_ptr<detail::PoolBase>> pools_;  // indexed by component type id
};

}  // namespace phaco
