#include "procedures/trainer/desktop_input.hpp"

#include <algorithm>
#include <cmath>

#include "procedures/scene/port_pivot.hpp"

namespace phaco {

namespace {

size_t at(Hand h) {
  return static_cast<size_t>(h) & 1u;
}

double dead(double a, double zone) {
  if (!std::isfinite(a) || std::abs(a) < zone) return 0.0;
  // Rescaled so the response starts at zero at the edge of the dead zone.
  return std::clamp((a - std::copysign(zone, a)) / (1.0 - zone), -1.0, 1.0);
}

// A trigger's −1 (released) .. 1 (full) as 0..1.
double trigger(float a) {
  return std::isfinite(a) ? std::clamp(0.5 * (a + 1.0), 0.0, 1.0) : 0.0;
}

// The press of `amount` 0..1 on `tool`: the forceps' grip or the probe's pedal.
void press(ToolPose& p, ToolKind tool, double amount) {
  if (tool == ToolKind::PhacoProbe || tool == ToolKind::Aspirator) {
    p.pedal = std::clamp(3.0 * amount, 0.0, 3.0);
  } else {
    p.grip = std::clamp(amount, 0.0, 1.0);
  }
}

}  // namespace

Vec3 clamp_to_workspace(const Vec3& p, const DesktopMapping& m) {
  Vec3 out = p;
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(out[i])) out[i] = 0.0;
    out[i] = std::clamp(out[i], m.workspace_min_mm[i], m.workspace_max_mm[i]);
  }
  return out;
}

ToolPose map_mouse_move(const ToolPose& pose, double dx_px, double dy_px, const DesktopMapping& m) {
  ToolPose p = pose;
  if (!std::isfinite(dx_px) || !std::isfinite(dy_px)) return p;
  // Screen right is +x (3 o'clock), screen down is −y (toward 6 o'clock).
  p.pos = clamp_to_workspace(pose.pos + Vec3(dx_px, -dy_px, 0.0) * m.mm_per_pixel, m);
  return p;
}

ToolPose map_wheel(const ToolPose& pose, double clicks, const DesktopMapping& m) {
  ToolPose p = pose;
  if (!std::isfinite(clicks)) return p;
  p.pos = clamp_to_workspace(pose.pos - Vec3::UnitZ() * (clicks * m.depth_mm_per_click), m);
  return p;
}

ToolPose map_buttons(const ToolPose& pose, ToolKind tool, bool left, bool right) {
  ToolPose p = pose;
  if (tool == ToolKind::PhacoProbe || tool == ToolKind::Aspirator) {
    p.pedal = left ? 3.0 : right ? 2.0 : 0.0;
  } else {
    p.grip = left ? 1.0 : 0.0;
  }
  return p;
}

ToolPose map_gamepad(const ToolPose& pose, ToolKind tool, Hand hand, const GamepadState& pad,
                     double dt_s, const DesktopMapping& m) {
  ToolPose p = pose;
  if (!std::isfinite(dt_s) || dt_s <= 0) return p;
  dt_s = std::min(dt_s, 0.1);  // a stalled UI frame must not throw the tool across the eye
  const bool left = hand == Hand::Left;
  const double ax =
      dead(pad.axes[left ? GamepadState::kLeftX : GamepadState::kRightX], m.stick_dead_zone);
  const double ay =
      dead(pad.axes[left ? GamepadState::kLeftY : GamepadState::kRightY], m.stick_dead_zone);
  const bool deeper = pad.buttons[left ? GamepadState::kLeftBumper : GamepadState::kRightBumper];
  const bool shallower = pad.buttons[left ? GamepadState::kLeftThumb : GamepadState::kRightThumb];
  const double dz = (shallower ? 1.0 : 0.0) - (deeper ? 1.0 : 0.0);
  const Vec3 v(ax * m.stick_speed_mm_s, -ay * m.stick_speed_mm_s, dz * m.depth_speed_mm_s);
  p.pos = clamp_to_workspace(pose.pos + v * dt_s, m);
  press(p, tool,
        trigger(pad.axes[left ? GamepadState::kLeftTrigger : GamepadState::kRightTrigger]));
  return p;
}

DesktopInput::DesktopInput(const DesktopMapping& mapping) : mapping_(mapping) {
  for (Hand h : {Hand::Left, Hand::Right}) publish(h);
}

void DesktopInput::publish(Hand hand) {
  Slot& s = slots_[at(hand)];
  const auto& port = port_[at(hand)];
  const ToolPose p =
      port ? pivot_in_port(pose_[at(hand)], *port, tool_[at(hand)]) : pose_[at(hand)];
  const uint64_t seq = s.seq.load(std::memory_order_relaxed);
  s.seq.store(seq + 1, std::memory_order_relaxed);  // odd: a write in progress
  // Release fence: a reader that sees any field below also sees the odd sequence first.
  std::atomic_thread_fence(std::memory_order_release);
  const double v[9] = {p.pos.x(),  p.pos.y(),  p.pos.z(), p.quat.w(), p.quat.x(),
                       p.quat.y(), p.quat.z(), p.grip,    p.pedal};
  for (size_t i = 0; i < 9; ++i) s.v[i].store(v[i], std::memory_order_relaxed);
  // Release: the fields are visible before the even sequence that says they are complete.
  s.seq.store(seq + 2, std::memory_order_release);
}

uint64_t DesktopInput::read_pose(Hand hand, ToolPose& out) const {
  const Slot& s = slots_[at(hand)];
  double v[9];
  uint64_t before = 0;
  for (;;) {
    // Acquire: pairs with the writer's final release; the fields read below are at least that
    // write's.
    before = s.seq.load(std::memory_order_acquire);
    if (before & 1u) continue;  // the writer is mid-write (a few stores): try again
    for (size_t i = 0; i < 9; ++i) v[i] = s.v[i].load(std::memory_order_relaxed);
    // Acquire fence: the field loads happen before the re-read of the sequence.
    std::atomic_thread_fence(std::memory_order_acquire);
    if (s.seq.load(std::memory_order_relaxed) == before) break;
  }
  out.pos = Vec3(v[0], v[1], v[2]);
  out.quat = Quat(v[3], v[4], v[5], v[6]);
  out.grip = v[7];
  out.pedal = v[8];
  return before;
}

void DesktopInput::set_start(Hand hand, ToolKind tool, const ToolPose& pose) {
  tool_[at(hand)] = tool;
  set_hand_pose(hand, pose);
}

void DesktopInput::set_port(Hand hand, const std::optional<EyePort>& port) {
  port_[at(hand)] = port;
  publish(hand);
}

void DesktopInput::set_hand_pose(Hand hand, const ToolPose& pose) {
  ToolPose p = pose;
  p.pos = clamp_to_workspace(pose.pos, mapping_);
  if (!(p.quat.norm() > 0.5)) p.quat = Quat::Identity();
  p.quat.normalize();
  p.grip = std::isfinite(p.grip) ? std::clamp(p.grip, 0.0, 1.0) : 0.0;
  p.pedal = std::isfinite(p.pedal) ? std::clamp(p.pedal, 0.0, 3.0) : 0.0;
  pose_[at(hand)] = p;
  publish(hand);
}

void DesktopInput::mouse_move(double dx_px, double dy_px) {
  const Hand h = selected();
  pose_[at(h)] = map_mouse_move(pose_[at(h)], dx_px, dy_px, mapping_);
  publish(h);
}

void DesktopInput::wheel(double clicks) {
  const Hand h = selected();
  pose_[at(h)] = map_wheel(pose_[at(h)], clicks, mapping_);
  publish(h);
}

void DesktopInput::mouse_buttons(bool left, bool right) {
  const Hand h = selected();
  pose_[at(h)] = map_buttons(pose_[at(h)], tool_[at(h)], left, right);
  publish(h);
}

void DesktopInput::switch_hand() {
  select(selected() == Hand::Left ? Hand::Right : Hand::Left);
}

void DesktopInput::select(Hand hand) {
  // The hand being left lets go: a held button must not stay pressed on a hand no longer driven.
  const Hand old = selected();
  if (old != hand) {
    pose_[at(old)] = map_buttons(pose_[at(old)], tool_[at(old)], false, false);
    publish(old);
  }
  selected_.store(static_cast<uint8_t>(hand), std::memory_order_relaxed);
}

void DesktopInput::gamepad(const GamepadState& pad, double dt_s) {
  for (Hand h : {Hand::Left, Hand::Right}) {
    pose_[at(h)] = map_gamepad(pose_[at(h)], tool_[at(h)], h, pad, dt_s, mapping_);
    publish(h);
  }
}

DesktopDevice::DesktopDevice(std::shared_ptr<const DesktopInput> input, Hand hand)
    : input_(std::move(input)), hand_(hand) {}

DeviceLimits DesktopDevice::limits() const {
  DeviceLimits l;
  l.has_force = false;  // a mouse renders no force
  l.workspace_min_mm = input_->mapping().workspace_min_mm;
  l.workspace_max_mm = input_->mapping().workspace_max_mm;
  return l;
}

void DesktopDevice::start(int64_t) {
  seq_ = 0;
  started_.store(true, std::memory_order_relaxed);
}

bool DesktopDevice::read(int64_t now_ns, DeviceSample& out) {
  if (!started_.load(std::memory_order_relaxed)) return false;
  ToolPose p;
  input_->read_pose(hand_, p);
  out = sample_of(p, now_ns, ++seq_);
  accepted_.fetch_add(1, std::memory_order_relaxed);
  return true;
}

DeviceHealth DesktopDevice::health(int64_t) const {
  return started_.load(std::memory_order_relaxed) ? DeviceHealth::Ok : DeviceHealth::Silent;
}

DeviceCounters DesktopDevice::counters() const {
  DeviceCounters c;
  c.accepted = accepted_.load(std::memory_order_relaxed);
  return c;
}

}  // namespace phaco
