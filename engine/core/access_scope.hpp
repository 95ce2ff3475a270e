#pragma once
// What the running system declared it touches, for the check of declared access against real
// access (issue 17 item 4). The frame graph trusts each SystemDesc's reads and writes; a system
// that looks up a component it did not declare (capsule_dynamics reading the capsule's triangles,
// say) races with whatever the graph lets run beside it, and nothing would show it. So, where the
// check is on, the executor installs the running system's scope on the thread that runs it, and
// every World lookup reports the access name of what it finds ("capsule.particles",
// "tools.pose"); an undeclared one throws std::logic_error naming the system and the component.
//
// Lives in engine/core so that engine/ecs (which reports) and engine/schedule (which checks) need
// not know each other. Lookups from tasks a system spawns on other threads (inside parallel_for)
// are not seen: systems look their components up before they split their loops.
//
// Thread-safety: the scope pointer is thread_local; a scope itself is read-only while installed.
#include <string_view>

namespace phaco {

class AccessScope {
 public:
  virtual ~AccessScope() = default;
  // Throws std::logic_error if `access_name` is in neither the system's reads nor its writes.
  virtual void touch(std::string_view access_name) const = 0;
};

namespace detail {
// The scope of the system running on this thread, or null (no check, or no system running).
inline thread_local const AccessScope* current_access_scope = nullptr;
}  // namespace detail

// Installs a scope on this thread for its lifetime and restores the previous one after (a worker
// waiting inside one system's parallel loop may run another system's task).
class AccessScopeGuard {
 public:
  explicit AccessScopeGuard(const AccessScope* scope) : previous_(detail::current_access_scope) {
    detail::current_access_scope = scope;
  }
  ~AccessScopeGuard() { detail::current_access_scope = previous_; }
  AccessScopeGuard(const AccessScopeGuard&) = delete;
  AccessScopeGuard& operator=(const AccessScopeGuard&) = delete;

 private:
  const AccessScope* previous_;
};

}  // namespace phaco
