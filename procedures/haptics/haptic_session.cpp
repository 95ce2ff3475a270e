#include "procedures/haptics/haptic_session.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include "engine/core/clock.hpp"
#include "engine/haptics/sample_bounds.hpp"
#include "engine/io/tool_shape.hpp"

namespace phaco {
namespace {

// Relaxed max on an atomic double: one writer (the haptic thread), readers only report it.
void raise_to(std::atomic<double>& a, double v) {
  if (v > a.load(std::memory_order_relaxed)) a.store(v, std::memory_order_relaxed);
}

bool finite(const Vec3& v) {
  return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z());
}

}  // namespace

HapticSession::HapticSession(const HapticSessionConfig& config) : config_(config) {
  for (HandRuntime& h : hands_) {
    h.state = std::make_unique<haptic_model::HapticToolState>();
    h.ring = std::make_unique<SpscRing<RingSample, kRingCapacity>>();
  }
}

HapticSession::~HapticSession() {
  stop();
}

void HapticSession::attach(Hand hand, std::unique_ptr<Device> device) {
  if (running()) throw std::logic_error("HapticSession::attach: the session is running");
  HandRuntime& h = hands_[index(hand)];
  h.device = std::move(device);
  if (h.device) {
    // The force the model may ask for is what the device can render.
    config_.model.max_force_mn =
        std::min(config_.model.max_force_mn, h.device->limits().max_force_mn);
  }
}

void HapticSession::start() {
  if (running()) return;
  const int64_t now = now_ns();
  for (HandRuntime& h : hands_) {
    if (h.device) h.device->start(now);
  }
  loop_.start(&HapticSession::tick_entry, this, config_.loop);
}

void HapticSession::stop() {
  loop_.stop();
  for (HandRuntime& h : hands_) {
    if (h.device) {
      h.device->write_force(Vec3::Zero(), now_ns());  // leave the hand free
      h.device->stop();
    }
  }
}

void HapticSession::tick_entry(void* self, const TickInfo& info) {
  static_cast<HapticSession*>(self)->tick(info);
}

void HapticSession::tick(const TickInfo& info) {
  // The newest model for every hand at once, so both hands feel the same frame.
  const bool fresh = models_.acquire();
  const HapticModel& model = models_.read_slot();
  const double dt = static_cast<double>(config_.loop.period_ns) * 1e-9;
  const double alpha = 1.0 - std::exp(-2.0 * std::numbers::pi * config_.velocity_cutoff_hz * dt);

  for (size_t k = 0; k < kHapticTools; ++k) {
    HandRuntime& h = hands_[k];
    if (!h.device) continue;
    Device& device = *h.device;
    h.ticks.fetch_add(1, std::memory_order_relaxed);
    const HapticTool& tool = model.tools[k];
    if (fresh) {
      haptic_model::adopt_model(tool, *h.state, config_.model);
      h.adopted.fetch_add(1, std::memory_order_relaxed);
    }

    const int64_t now = info.wake_ns;
    DeviceSample s;
    bool new_sample = false;
    if (device.read(now, s) && (!h.read_any || s.seq != h.last_seq)) {
      h.read_any = true;
      h.last_seq = s.seq;  // a dropped sample read again next tick is not counted again
      switch (bound_sample(s)) {
        case SampleCheck::Ok:
          new_sample = true;
          break;
        case SampleCheck::Clamped:
          new_sample = true;
          h.samples_clamped.fetch_add(1, std::memory_order_relaxed);
          break;
        case SampleCheck::NonFinite:
          h.non_finite.fetch_add(1, std::memory_order_relaxed);
          break;
        case SampleCheck::OutsideWorkspace:
          h.outside_workspace.fetch_add(1, std::memory_order_relaxed);
          break;
      }
    }
    // A dropped sample changes nothing below: the tool and the force follow the last good one.
    if (new_sample) {
      if (h.have_sample && s.t_ns > h.last_sample_ns) {
        const Vec3 v =
            (s.pos_mm - h.last_pos) / (static_cast<double>(s.t_ns - h.last_sample_ns) * 1e-9);
        if (finite(v)) h.velocity += alpha * (v - h.velocity);
      }
      h.sample = s;
      h.have_sample = true;
      h.last_sample_ns = s.t_ns;
      h.last_pos = s.pos_mm;
      h.ring->try_push(RingSample{
          {s.pos_mm.x(), s.pos_mm.y(), s.pos_mm.z()},
          {s.quat.w(), s.quat.x(), s.quat.y(), s.quat.z()},
          s.grip,
          s.pedal});  // a full ring counts the drop; the simulation only needs the newest
      h.samples.fetch_add(1, std::memory_order_relaxed);
    }

    const DeviceHealth health = device.health(now);
    Vec3 force = Vec3::Zero();
    if (h.have_sample && (health == DeviceHealth::Ok || health == DeviceHealth::Ended)) {
      // The shaft the device holds (local +z, tip → handle): the port's lever (issue 20 item 2).
      // Its axis runs beside the tip by the tool's bent point, turned with the device
      // (engine/io/tool_shape): the line the port holds, as the scene's tool_ports does.
      const bool oriented = h.sample.quat.coeffs().allFinite() && h.sample.quat.norm() > 1e-9;
      const Quat q = oriented ? h.sample.quat.normalized() : Quat::Identity();
      const Vec3 shaft = oriented ? Vec3(q * Vec3::UnitZ()) : Vec3::Zero();
      const Vec3 bend = oriented
                            ? Vec3(q * shaft_offset_local(static_cast<ToolKind>(tool.tool_kind)))
                            : Vec3::Zero();
      const haptic_model::HapticForce f = haptic_model::haptic_tick(
          tool, h.sample.pos_mm, h.velocity, shaft, bend, config_.model, *h.state);
      force = f.force_mn;
      if (f.clamped) h.clamped.fetch_add(1, std::memory_order_relaxed);
      if (f.input_rejected) h.rejected.fetch_add(1, std::memory_order_relaxed);
    } else {
      // Silent or failed: the tool stays where it was (newest_pose keeps the last sample) and the
      // hand is let go at once, within this tick.
      h.zero_force_ticks.fetch_add(1, std::memory_order_relaxed);
      h.velocity = Vec3::Zero();
    }
    // The device judges its health at the same instant as above, so the two never disagree.
    device.write_force(force, now);
    if (new_sample) h.latency.record(now_ns() - h.sample.t_ns);

    raise_to(h.max_force_mn, force.norm());
    raise_to(h.max_force_step_mn, (force - h.force).norm());
    h.force = force;
    h.force_x.store(static_cast<float>(force.x()), std::memory_order_relaxed);
    h.force_y.store(static_cast<float>(force.y()), std::memory_order_relaxed);
    h.force_z.store(static_cast<float>(force.z()), std::memory_order_relaxed);
  }
}

void HapticSession::step(const TickInfo& info) {
  if (running()) throw std::logic_error("HapticSession::step: the 1 kHz thread is running");
  tick(info);
}

bool HapticSession::newest_pose(Hand hand, ToolPose& pose) {
  HandRuntime& h = hands_[index(hand)];
  if (!h.device) return false;
  RingSample s;
  while (h.ring->try_pop(s)) {
    h.pose.pos = Vec3(s.pos[0], s.pos[1], s.pos[2]);
    h.pose.quat = Quat(s.quat[0], s.quat[1], s.quat[2], s.quat[3]);
    h.pose.grip = s.grip;
    h.pose.pedal = s.pedal;
    h.pose_valid = true;
  }
  if (!h.pose_valid) return false;  // no sample yet: the scene holds the tool at its start
  pose = h.pose;                    // held while the device is silent: the tool freezes
  return true;
}

void HapticSession::publish_model() {
  const int64_t now = now_ns();
  if (config_.min_model_interval_ms > 0 &&
      static_cast<double>(now - last_publish_ns_) < config_.min_model_interval_ms * 1e6) {
    return;  // too soon: the slot is filled again next frame
  }
  last_publish_ns_ = now;
  models_.publish();
  published_.fetch_add(1, std::memory_order_relaxed);
}

Vec3 HapticSession::last_force(Hand hand) const {
  const HandRuntime& h = hands_[index(hand)];
  return {h.force_x.load(std::memory_order_relaxed), h.force_y.load(std::memory_order_relaxed),
          h.force_z.load(std::memory_order_relaxed)};
}

HapticSessionStats HapticSession::stats() const {
  HapticSessionStats out;
  out.realtime = loop_.realtime_status();
  out.loop = loop_.stats();
  out.spin_margin_ns = loop_.spin_margin_ns();
  out.models_published = published_.load(std::memory_order_relaxed);
  const int64_t now = now_ns();
  for (size_t k = 0; k < kHapticTools; ++k) {
    const HandRuntime& h = hands_[k];
    HapticHandStats& s = out.hands[k];
    s.attached = h.device != nullptr;
    if (!s.attached) continue;
    s.health = h.device->health(now);
    s.counters = h.device->counters();
    s.ticks = h.ticks.load(std::memory_order_relaxed);
    s.samples = h.samples.load(std::memory_order_relaxed);
    s.samples_dropped = h.ring->dropped();
    s.samples_non_finite = h.non_finite.load(std::memory_order_relaxed);
    s.samples_outside_workspace = h.outside_workspace.load(std::memory_order_relaxed);
    s.samples_clamped = h.samples_clamped.load(std::memory_order_relaxed);
    s.zero_force_ticks = h.zero_force_ticks.load(std::memory_order_relaxed);
    s.models_adopted = h.adopted.load(std::memory_order_relaxed);
    s.clamped_ticks = h.clamped.load(std::memory_order_relaxed);
    s.rejected_inputs = h.rejected.load(std::memory_order_relaxed);
    s.max_force_mn = h.max_force_mn.load(std::memory_order_relaxed);
    s.max_force_step_mn = h.max_force_step_mn.load(std::memory_order_relaxed);
    s.latency = h.latency.summary();
  }
  return out;
}

}  // namespace phaco
