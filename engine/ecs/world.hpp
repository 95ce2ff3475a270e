#pragma once
// The World: bodies and tools as entities (generational handles) with their components.
//
// Entities are few (a handful of bodies and tools); their elements (particles, springs, tets...)
// live in flat SoA tables inside components, so per-entity lookups here are never on a hot path.
// Component storage is one pool per type: entity index -> component, iterated in entity-index
// order so that every walk over the world is deterministic.
//
// Thread-safety (issue 22), stated on every public method below as "Thread:":
//   - structural: create, destroy, add, remove, name_component change the pools; only with no
//     system running, i.e. while the scene is built or from CommandQueues::apply at the frame's
//     sync point;
//   - lookup: alive, kind, name, find, entities, entity_count, get, at, has, each, access_name
//     may run from several systems at once, as the frame graph schedules them: they read the
//     pools without changing them. What they return is shared by the systems that declared it;
//     two systems writing one component never run together (the graph is built from SystemDesc
//     reads/writes, checked in debug builds).
#include <cassert>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "engine/core/access_scope.hpp"
#include "engine/core/handle.hpp"
#include "engine/core/table.hpp"

namespace phaco {

using Entity = Handle;

enum class EntityKind : uint8_t { Body, Tool };

// How a component type is named in SystemDesc reads and writes (DESIGN.md §4), for the check of
// declared access (engine/core/access_scope.hpp):
//   PerEntity  "<owner>.<name>", owner the body's entity name ("capsule.particles"), or "tools"
//              for any tool ("tools.pose");
//   Global     "<name>" whichever entity holds it (a drill's record kept on a body: "metrics");
//   Constant   set when the scene is built and never written by a system (a tool's kind): reading
//              it needs no declaration.
enum class AccessKind : uint8_t { PerEntity, Global, Constant };

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
  // Thread: structural (no system running).
  Entity create(EntityKind kind, std::string name);
  // Removes the entity and all its components; false if it was already gone (stale handle).
  // Thread: structural.
  bool destroy(Entity e);
  // False for a null, stale or destroyed handle. Thread: lookup.
  bool alive(Entity e) const {
    // Entities are never compacted, so a slot's generation only grows: a handle past the table or
    // ahead of its slot's generation was made by another World, and would read as merely stale.
    assert((e.is_null() || (e.index < entities_.slots.size() &&
                            e.generation <= entities_.slots.generation(e.index))) &&
           "an entity handle from another World");
    return entities_.slots.valid(e);
  }
  // Thread: lookup; std::logic_error for a stale handle.
  EntityKind kind(Entity e) const { return entities_.kind[checked(e)]; }
  // Thread: lookup; std::logic_error for a stale handle.
  const std::string& name(Entity e) const { return entities_.name[checked(e)]; }
  // Thread: lookup.
  std::optional<Entity> find(std::string_view name) const;
  // Live entities in index order. Thread: lookup.
  std::vector<Entity> entities() const;
  // Thread: lookup.
  uint32_t entity_count() const { return entities_.slots.live_count(); }

  // Replaces e's C if it has one. Thread: structural.
  template <class C>
  C& add(Entity e, C component) {
    auto& pool = pool_for<C>();
    const uint32_t i = checked(e);
    if (pool.by_entity.size() <= i) pool.by_entity.resize(i + 1);
    pool.by_entity[i] = std::move(component);
    return *pool.by_entity[i];
  }
  // Null when e has no C. Inside a system whose access is checked, a found component's access
  // name must be among the system's reads or writes (std::logic_error otherwise). Thread: lookup;
  // the component itself only by the systems that declared it.
  template <class C>
  C* get(Entity e) {
    C* c = lookup<C>(e);
    if (c && detail::current_access_scope) report_access(e, detail::component_type_id<C>());
    return c;
  }
  template <class C>
  const C* get(Entity e) const {
    return const_cast<World*>(this)->get<C>(e);
  }
  // Like get, but a missing component is a programming error. Thread: lookup, as get.
  template <class C>
  C& at(Entity e) {
    C* c = get<C>(e);
    if (!c) throw std::logic_error("entity '" + name(e) + "' has no such component");
    return *c;
  }
  // Whether e has C: structure, not the component's data, so not an access to declare.
  // Thread: lookup.
  template <class C>
  bool has(Entity e) const {
    return const_cast<World*>(this)->lookup<C>(e) != nullptr;
  }
  // Thread: structural.
  template <class C>
  bool remove(Entity e) {
    auto* pool = find_pool<C>();
    return pool && alive(e) && pool->erase(e.index);
  }
  // f(Entity, C&) for every live entity that has C, in entity-index order. Thread: lookup, as
  // get; f must not make structural calls.
  template <class C, class F>
  void each(F&& f) {
    auto* pool = find_pool<C>();
    if (!pool) return;
    for (uint32_t i = 0; i < pool->by_entity.size(); ++i) {
      if (!pool->by_entity[i] || !entities_.slots.alive(i)) continue;
      const Entity e = entities_.slots.handle(i);
      if (detail::current_access_scope) report_access(e, detail::component_type_id<C>());
      f(e, *pool->by_entity[i]);
    }
  }

  // Names C for the check of declared access (AccessKind above). A scene names every component
  // type its systems look up; a lookup of an unnamed type inside a checked system is an error.
  // Thread: structural.
  template <class C>
  void name_component(std::string name, AccessKind kind = AccessKind::PerEntity) {
    const uint32_t id = detail::component_type_id<C>();
    if (access_.size() <= id) access_.resize(id + 1);
    access_[id] = ComponentAccess{std::move(name), kind};
  }
  // The access name of e's C as SystemDesc lists it; empty for a Constant type. Thread: lookup.
  template <class C>
  std::string access_name(Entity e) const {
    return access_name(e, detail::component_type_id<C>());
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

  struct ComponentAccess {
    std::string name;  // empty: not named
    AccessKind kind = AccessKind::PerEntity;
  };

  std::string access_name(Entity e, uint32_t type_id) const;
  void report_access(Entity e, uint32_t type_id) const;
  template <class C>
  C* lookup(Entity e) {
    auto* pool = find_pool<C>();
    if (!pool || !alive(e) || e.index >= pool->by_entity.size() || !pool->by_entity[e.index]) {
      return nullptr;
    }
    return &*pool->by_entity[e.index];
  }
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
  std::vector<ComponentAccess> access_;                   // indexed by component type id
};

}  // namespace phaco
