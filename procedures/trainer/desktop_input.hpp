#pragma once
// Mouse, keyboard and gamepad as haptic devices (issue 8 item 3): what a low-cost PC has drives
// the two hands through the SAME 1 kHz loop and handoff as a haptic device (DESIGN.md §5).
//
//   main (UI) thread ── DesktopInput::mouse_move / wheel / buttons / gamepad ──▶ per-hand seqlock
//   haptic thread    ── DesktopDevice::read (one per hand) ◀── the newest pose ──┘
//
// Mapping (frame of DESIGN.md §6: +x 3 o'clock, +y 12 o'clock, +z toward the surgeon; the
// microscope looks down −z, so the screen's right is +x and the screen's up is +y):
//   mouse      x/y move the SELECTED hand's tip in the microscope plane, mm_per_pixel mm per
//              pixel (screen y grows downward: −y); the wheel is depth, depth_mm_per_click per
//              click, a click forward (+1) goes deeper (−z); the left button closes the forceps
//              (grip 1) or, on the phaco probe, presses the pedal to 3 (ultrasound), the right
//              button the probe's pedal 2 (aspiration); a key (the UI's choice) switch_hand().
//   gamepad    (GLFW's gamepad layout) left stick → left hand, right stick → right hand, x/y at
//              stick_speed_mm_s at full deflection (rate control, dead zone stick_dead_zone);
//              shoulder buttons (LB/RB) take their hand deeper, stick clicks (L3/R3) shallower,
//              at depth_speed_mm_s; the triggers (LT/RT) grip the forceps 0..1 or set the probe's
//              pedal 0..3 in proportion.
// Tips stay in a box about the eye (workspace_*); the shaft keeps the scenario's first pose's
// orientation, or, for a hand given a port (set_port: the trainer's default when the drill has
// ports), pivots in it once the tip is in the eye (procedures/scene/port_pivot). Every pose starts
// at the scenario's first track pose (set_start_pose).
//
// Thread safety: one writer thread (the UI) for all the mutators, any number of readers
// (read_pose). A seqlock per hand: the writer bumps the sequence to odd, writes the fields
// (relaxed atomics), bumps it to even with release; a reader retries while the sequence is odd or
// changed. Neither side locks or allocates; the writer never waits.
#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>

#include "components/eye_ports.hpp"
#include "engine/haptics/device.hpp"
#include "engine/io/scenario.hpp"
#include "engine/io/track.hpp"

namespace phaco {

struct DesktopMapping {
  double mm_per_pixel = 0.01;       // mouse: tip travel per pixel (a 1280 px wide view ≈ 13 mm)
  double depth_mm_per_click = 0.1;  // wheel
  double stick_speed_mm_s = 4.0;    // gamepad stick at full deflection
  double depth_speed_mm_s = 2.0;    // gamepad shoulder buttons
  double stick_dead_zone = 0.15;    // |axis| below this is zero
  Vec3 workspace_min_mm{-9.0, -9.0, -6.0};
  Vec3 workspace_max_mm{9.0, 9.0, 9.0};
};

// GLFW_GAMEPAD_* layout: axes LX, LY, RX, RY (−1..1, y down), LT, RT (−1 released .. 1);
// buttons A, B, X, Y, LB, RB, Back, Start, Guide, L3, R3, Up, Right, Down, Left.
struct GamepadState {
  std::array<float, 6> axes{0, 0, 0, 0, -1, -1};
  std::array<bool, 15> buttons{};
  static constexpr int kLeftX = 0, kLeftY = 1, kRightX = 2, kRightY = 3, kLeftTrigger = 4,
                       kRightTrigger = 5;
  static constexpr int kLeftBumper = 4, kRightBumper = 5, kLeftThumb = 9, kRightThumb = 10;
};

// Pure mapping, testable without a window or threads. `tool` decides whether the press is a grip
// or a pedal.
ToolPose map_mouse_move(const ToolPose& pose, double dx_px, double dy_px, const DesktopMapping& m);
ToolPose map_wheel(const ToolPose& pose, double clicks, const DesktopMapping& m);
ToolPose map_buttons(const ToolPose& pose, ToolKind tool, bool left, bool right);
// One hand from the gamepad over dt_s seconds of holding it.
ToolPose map_gamepad(const ToolPose& pose, ToolKind tool, Hand hand, const GamepadState& pad,
                     double dt_s, const DesktopMapping& m);
Vec3 clamp_to_workspace(const Vec3& p, const DesktopMapping& m);

class DesktopInput {
 public:
  explicit DesktopInput(const DesktopMapping& mapping = {});

  // Writer (UI thread). Before the session starts: each hand's tool and start pose (the
  // scenario's first track pose; the trainer session does this).
  void set_start(Hand hand, ToolKind tool, const ToolPose& pose);
  void set_hand_pose(Hand hand, const ToolPose& pose);  // absolute (clamped to the workspace)
  // The port `hand`'s shaft pivots in (nullopt: none, the shaft keeps its orientation).
  void set_port(Hand hand, const std::optional<EyePort>& port);
  void mouse_move(double dx_px, double dy_px);  // the selected hand
  void wheel(double clicks);                    // the selected hand; + = deeper
  void mouse_buttons(bool left, bool right);    // the selected hand
  void switch_hand();                           // the other hand becomes selected
  void select(Hand hand);
  void gamepad(const GamepadState& pad, double dt_s);  // both hands

  // Any thread.
  Hand selected() const { return static_cast<Hand>(selected_.load(std::memory_order_relaxed)); }
  // The newest pose of `hand` and its version (even, > 0 once set; changes on every write).
  // Lock-free, no allocation: for the haptic thread.
  uint64_t read_pose(Hand hand, ToolPose& out) const;

  const DesktopMapping& mapping() const { return mapping_; }

 private:
  struct alignas(64) Slot {
    std::atomic<uint64_t> seq{0};
    std::array<std::atomic<double>, 9> v{};  // pos xyz, quat wxyz, grip, pedal
  };
  void publish(Hand hand);

  DesktopMapping mapping_;
  // Writer thread only.
  std::array<ToolPose, 2> pose_{};
  std::array<ToolKind, 2> tool_{ToolKind::Forceps, ToolKind::Forceps};
  std::array<std::optional<EyePort>, 2> port_;
  std::array<Slot, 2> slots_;
  std::atomic<uint8_t> selected_{static_cast<uint8_t>(Hand::Right)};
};

// A Device per hand reading DesktopInput on the haptic thread: health Ok once started, a new
// sample (seq + 1, t = now) on every read so a recording has the pose at 1 kHz whether the mouse
// moves or not; a tracker (limits().has_force false): the force written is ignored.
class DesktopDevice final : public Device {
 public:
  DesktopDevice(std::shared_ptr<const DesktopInput> input, Hand hand);
  std::string_view name() const override { return "desktop"; }
  DeviceLimits limits() const override;
  void start(int64_t now_ns) override;
  void stop() override { started_.store(false, std::memory_order_relaxed); }
  bool read(int64_t now_ns, DeviceSample& out) override;
  void write_force(const Vec3&, int64_t) override {}
  DeviceHealth health(int64_t now_ns) const override;
  DeviceCounters counters() const override;

 private:
  std::shared_ptr<const DesktopInput> input_;
  Hand hand_;
  std::atomic<bool> started_{false};
  uint32_t seq_ = 0;                   // haptic thread only
  std::atomic<uint64_t> accepted_{0};  // relaxed: a statistic
};

}  // namespace phaco
