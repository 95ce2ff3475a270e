#include "engine/ecs/world.hpp"

#include <atomic>

namespace phaco {

namespace detail {
uint32_t next_component_type_id() {
  static std::atomic<uint32_t> next{0};
  return next.fetch_add(1, std::memory_order_relaxed);  // only uniqueness matters
}
}  // namespace detail

Entity World::create(EntityKind kind, std::string name) {
  const uint32_t i = table_add(entities_);
  entities_.kind[i] = kind;
  entities_.name[i] = std::move(name);
  return entities_.slots.handle(i);
}

bool World::destroy(Entity e) {
  if (!alive(e)) return false;
  for (auto& pool : pools_) {
    if (pool) pool->erase(e.index);
  }
  entities_.name[e.index].clear();
  return table_remove(entities_, e.index);
}

std::optional<Entity> World::find(std::string_view name) const {
  for (uint32_t i = 0; i < entities_.slots.size(); ++i) {
    if (entities_.slots.alive(i) && entities_.name[i] == name) return entities_.slots.handle(i);
  }
  return std::nullopt;
}

std::vector<Entity> World::entities() const {
  std::vector<Entity> out;
  out.reserve(entities_.slots.live_count());
  for (uint32_t i = 0; i < entities_.slots.size(); ++i) {
    if (entities_.slots.alive(i)) out.push_back(entities_.slots.handle(i));
  }
  return out;
}

std::string World::access_name(Entity e, uint32_t type_id) const {
  if (type_id >= access_.size() || access_[type_id].name.empty()) {
    return name(e) + ".<component type " + std::to_string(type_id) +
           " has no access name: World::name_component>";
  }
  const ComponentAccess& a = access_[type_id];
  switch (a.kind) {
    case AccessKind::Constant:
      return {};
    case AccessKind::Global:
      return a.name;
    case AccessKind::PerEntity:
      break;
  }
  return (kind(e) == EntityKind::Tool ? std::string("tools") : name(e)) + "." + a.name;
}

void World::report_access(Entity e, uint32_t type_id) const {
  const AccessScope* scope = detail::current_access_scope;
  if (!scope) return;
  const std::string n = access_name(e, type_id);
  if (!n.empty()) scope->touch(n);
}

}  // namespace phaco
