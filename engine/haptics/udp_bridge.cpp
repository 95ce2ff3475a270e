// The bridge device: its I/O thread and the haptic thread's side (issue 6 item 4). The codec is
// udp_protocol.cpp, the seqlock seqlock.hpp, the socket helpers udp_socket.cpp, the peer
// udp_bridge_peer.cpp.
#include "engine/haptics/udp_bridge.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>
#include <thread>

#include "engine/core/clock.hpp"
#include "engine/core/error.hpp"
#include "engine/haptics/sample_bounds.hpp"
#include "engine/haptics/seqlock.hpp"
#include "engine/haptics/udp_socket.hpp"

namespace phaco {

namespace {

using namespace udp_protocol;
using udp_socket::bind_udp;
using udp_socket::resolve_ipv4;
using udp_socket::same_endpoint;

// Plain data for the seqlocks (Eigen types are not trivially copyable).
struct PosePayload {
  int64_t t_ns;  // receive time
  uint32_t seq, buttons;
  double pos[3];
  double quat[4];  // w, x, y, z
  double grip, pedal;
  uint64_t sender_time_us;
};
struct ForcePayload {
  double force_mn[3];
  uint64_t ack_sender_time_us;
  uint32_t ack_seq;
  uint32_t health;
};

}  // namespace

// ---------------------------------------------------------------------------------------------
// The device
// ---------------------------------------------------------------------------------------------
struct UdpBridgeDevice::Impl {
  UdpBridgeConfig config;
  int fd = -1;
  uint16_t local_port = 0;
  sockaddr_in peer{};
  int64_t silence_ns = 0;
  int64_t max_age_us = 0;

  std::thread io_thread;
  // Release/acquire: stop() publishes the request; the I/O thread sees it on its next pass.
  std::atomic<bool> running{false};
  // Relaxed: a flag read on the next tick; nothing else is published with it.
  std::atomic<bool> failed{false};

  // I/O thread → haptic thread.
  Seqlock<PosePayload> pose;
  // Receive time of the newest accepted packet, 0 = never. Relaxed: a timestamp compared with
  // the clock; the pose itself travels through the seqlock.
  std::atomic<int64_t> last_accept_ns{0};
  // Haptic thread → I/O thread.
  Seqlock<ForcePayload> force;

  // Counters: written by the I/O thread (silences by the haptic thread), read by anyone.
  // Relaxed: statistics, ordering nothing.
  std::atomic<uint64_t> accepted{0}, malformed{0}, bad_checksum{0}, wrong_version{0}, wrong_peer{0},
      non_finite{0}, out_of_workspace{0}, duplicate{0}, out_of_order{0}, stale{0}, clamped{0},
      silences{0};

  // I/O thread only.
  bool have_seq = false;
  uint32_t newest_seq = 0;
  bool have_offset = false;
  int64_t offset_us = 0;         // min over accepted packets of (receive − sender) time, µs
  int64_t offset_update_ns = 0;  // when offset_us was last updated
  uint32_t last_sent_version = 0;
  bool last_sent_zero = true;
  uint32_t force_seq = 0;

  // Haptic thread only.
  DeviceSample held{};
  uint64_t held_sender_time_us = 0;
  bool have_held = false;
  bool was_silent = true;

  bool silent(int64_t now) const {
    const int64_t last = last_accept_ns.load(std::memory_order_relaxed);
    return last == 0 || now - last > silence_ns;
  }

  static void bump(std::atomic<uint64_t>& c) { c.fetch_add(1, std::memory_order_relaxed); }

  void handle(std::span<const uint8_t> bytes, const sockaddr_in& from, int64_t now) {
    if (!same_endpoint(from, peer)) return bump(wrong_peer);
    PoseMessage m;
    switch (decode(bytes, m)) {
      case DecodeStatus::Ok:
        break;
      case DecodeStatus::WrongVersion:
        return bump(wrong_version);
      case DecodeStatus::BadChecksum:
        return bump(bad_checksum);
      case DecodeStatus::Malformed:
      case DecodeStatus::WrongType:
        return bump(malformed);
    }
    if (config.device_id != 0 && m.device_id != config.device_id) return bump(wrong_peer);
    // The bounds every device sample meets (engine/haptics/sample_bounds.hpp), checked here too
    // so that a bad packet is counted as the packet it was and never becomes the newest sample.
    DeviceSample s;
    s.pos_mm = Vec3(m.pos_mm[0], m.pos_mm[1], m.pos_mm[2]);
    s.quat = Quat(m.quat[0], m.quat[1], m.quat[2], m.quat[3]);
    s.grip = m.grip;
    s.pedal = m.pedal;
    const SampleCheck bounds = bound_sample(s);
    if (bounds == SampleCheck::NonFinite) return bump(non_finite);
    if (bounds == SampleCheck::OutsideWorkspace) return bump(out_of_workspace);

    if (silent(now)) {  // after a silence the peer may have restarted: resynchronise
      have_seq = false;
      have_offset = false;
    }
    if (have_seq) {
      // Serial-number arithmetic: the signed difference is right across the 2^32 wrap as long
      // as the two are within 2^31 packets (24 days at 1 kHz).
      const int32_t ahead = static_cast<int32_t>(m.seq - newest_seq);
      if (ahead == 0) return bump(duplicate);
      if (ahead < 0) return bump(out_of_order);
    }
    const int64_t now_us = now / 1000;
    // Modular difference: the two clocks may have any epochs.
    const int64_t delay_us = static_cast<int64_t>(static_cast<uint64_t>(now_us) - m.sender_time_us);
    int64_t offset = delay_us;
    if (have_offset) {
      // Let the minimum rise by 100 µs per s (1e-4) to follow a drifting peer clock; saturated,
      // since a peer may send any time at all and offset_us may sit near the int64 limits.
      const int64_t rise_us = std::max<int64_t>(0, (now - offset_update_ns) / 10'000'000);
      const int64_t risen = offset_us > std::numeric_limits<int64_t>::max() - rise_us
                                ? std::numeric_limits<int64_t>::max()
                                : offset_us + rise_us;
      offset = std::min(risen, delay_us);
      // offset <= delay_us, so the age is >= 0 but may exceed the int64 range (a peer's time
      // jumping by more than 2^63 µs): the difference is taken unsigned, where it is exact.
      const uint64_t age_us = static_cast<uint64_t>(delay_us) - static_cast<uint64_t>(offset);
      if (age_us > static_cast<uint64_t>(max_age_us)) return bump(stale);
    }
    have_offset = true;
    offset_us = offset;
    offset_update_ns = now;
    have_seq = true;
    newest_seq = m.seq;

    PosePayload p{};
    p.t_ns = now;
    p.seq = m.seq;
    p.buttons = m.buttons;
    for (int i = 0; i < 3; ++i) p.pos[i] = s.pos_mm[i];
    p.quat[0] = s.quat.w(), p.quat[1] = s.quat.x(), p.quat[2] = s.quat.y(), p.quat[3] = s.quat.z();
    p.grip = s.grip;
    p.pedal = s.pedal;
    p.sender_time_us = m.sender_time_us;
    pose.store(p);
    last_accept_ns.store(now, std::memory_order_relaxed);
    bump(accepted);
    if (bounds == SampleCheck::Clamped) bump(clamped);
  }

  void send_force(const ForcePayload& f, bool zero, DeviceHealth h, int64_t now) {
    ForceMessage m;
    m.device_id = config.device_id;
    m.seq = ++force_seq;
    m.sender_time_us = static_cast<uint64_t>(now / 1000);
    for (int i = 0; i < 3; ++i) m.force_mn[i] = zero ? 0.0f : static_cast<float>(f.force_mn[i]);
    m.ack_seq = f.ack_seq;
    m.ack_sender_time_us = f.ack_sender_time_us;
    m.health = static_cast<uint8_t>(h);
    const Packet b = encode(m);
    // Best effort: a lost force packet is replaced by the next one a millisecond later.
    ::sendto(fd, b.data(), b.size(), MSG_DONTWAIT, reinterpret_cast<const sockaddr*>(&peer),
             sizeof peer);
    last_sent_zero = zero || (f.force_mn[0] == 0 && f.force_mn[1] == 0 && f.force_mn[2] == 0);
  }

  void io_loop() {
    std::array<uint8_t, 2048> buf{};
    while (running.load(std::memory_order_acquire)) {
      pollfd pfd{fd, POLLIN, 0};
      const int r = ::poll(&pfd, 1, 1);  // 1 ms: also the pace of force packets
      if (r < 0 && errno != EINTR) {
        failed.store(true, std::memory_order_relaxed);
        break;
      }
      if (r > 0) {
        for (;;) {
          sockaddr_in from{};
          socklen_t len = sizeof from;
          // MSG_TRUNC: the real length even when longer than buf, so oversize is "malformed".
          const ssize_t n = ::recvfrom(fd, buf.data(), buf.size(), MSG_DONTWAIT | MSG_TRUNC,
                                       reinterpret_cast<sockaddr*>(&from), &len);
          if (n < 0) break;  // EAGAIN: drained (other errors: retried on the next poll)
          const int64_t now = now_ns();
          if (static_cast<std::size_t>(n) > buf.size()) {
            if (!same_endpoint(from, peer)) {
              bump(wrong_peer);
            } else {
              bump(malformed);
            }
            continue;
          }
          handle(std::span<const uint8_t>(buf.data(), static_cast<std::size_t>(n)), from, now);
        }
      }
      const int64_t now = now_ns();
      const bool quiet = silent(now);
      const DeviceHealth h = failed.load(std::memory_order_relaxed) ? DeviceHealth::Failed
                             : quiet                                ? DeviceHealth::Silent
                                                                    : DeviceHealth::Ok;
      const uint32_t v = force.version();
      ForcePayload f{};
      if (v != last_sent_version && force.load(f)) {
        last_sent_version = v;
        send_force(f, quiet, h, now);  // zero while silent, whatever the haptic thread wrote
      } else if (quiet && !last_sent_zero) {
        force.load(f);
        send_force(f, true, h, now);  // went silent since the last packet: say zero now
      }
    }
  }
};

UdpBridgeDevice::UdpBridgeDevice(UdpBridgeConfig config) : impl_(std::make_unique<Impl>()) {
  Impl& d = *impl_;
  d.config = std::move(config);
  const std::string what = "udp device '" + d.config.name + "'";
  if (!(d.config.silence_timeout_ms > 0)) {
    throw InputError(what + ": silence_timeout_ms must be > 0");
  }
  if (!(d.config.max_age_ms > 0)) throw InputError(what + ": max_age_ms must be > 0");
  if (d.config.peer_port == 0) throw InputError(what + ": peer port must be in 1..65535, got 0");
  d.silence_ns = std::llround(d.config.silence_timeout_ms * 1e6);
  d.max_age_us = std::llround(d.config.max_age_ms * 1e3);
  d.peer = resolve_ipv4(d.config.peer_host, d.config.peer_port, what + ": peer");
  d.fd = bind_udp(d.config.bind_host, d.config.local_port, what, d.local_port);
}

UdpBridgeDevice::~UdpBridgeDevice() {
  stop();
  if (impl_->fd >= 0) ::close(impl_->fd);
}

std::string_view UdpBridgeDevice::name() const {
  return impl_->config.name;
}
DeviceLimits UdpBridgeDevice::limits() const {
  return impl_->config.limits;
}
uint16_t UdpBridgeDevice::local_port() const {
  return impl_->local_port;
}

void UdpBridgeDevice::start(int64_t /*now_ns*/) {
  if (impl_->io_thread.joinable()) return;
  impl_->running.store(true, std::memory_order_release);
  impl_->io_thread = std::thread([d = impl_.get()] { d->io_loop(); });
}

void UdpBridgeDevice::stop() {
  impl_->running.store(false, std::memory_order_release);
  if (impl_->io_thread.joinable()) impl_->io_thread.join();
}

bool UdpBridgeDevice::read(int64_t now_ns, DeviceSample& out) {
  Impl& d = *impl_;
  if (d.silent(now_ns) || d.failed.load(std::memory_order_relaxed)) {
    if (!d.was_silent && d.have_held) Impl::bump(d.silences);
    d.was_silent = true;
    if (!d.have_held) return false;
    out = d.held;  // frozen at the last good pose
    return true;
  }
  d.was_silent = false;
  PosePayload p;
  if (d.pose.load(p)) {  // else a write was in progress: keep the previous one this tick
    d.held.t_ns = p.t_ns;
    d.held.seq = p.seq;
    d.held.pos_mm = Vec3(p.pos[0], p.pos[1], p.pos[2]);
    d.held.quat = Quat(p.quat[0], p.quat[1], p.quat[2], p.quat[3]);
    d.held.grip = p.grip;
    d.held.pedal = p.pedal;
    d.held.buttons = p.buttons;
    d.held_sender_time_us = p.sender_time_us;
    d.have_held = true;
  }
  if (!d.have_held) return false;
  out = d.held;
  return true;
}

void UdpBridgeDevice::write_force(const Vec3& force_mn, int64_t now_ns) {
  Impl& d = *impl_;
  const DeviceHealth h = health(now_ns);
  const Vec3 f = (h == DeviceHealth::Ok && d.config.limits.has_force)
                     ? clamp_force(force_mn, d.config.limits.max_force_mn)
                     : Vec3::Zero();
  ForcePayload p{};
  for (int i = 0; i < 3; ++i) p.force_mn[i] = f[i];
  p.ack_seq = d.have_held ? d.held.seq : 0;
  p.ack_sender_time_us = d.have_held ? d.held_sender_time_us : 0;
  p.health = static_cast<uint32_t>(h);
  d.force.store(p);
}

DeviceHealth UdpBridgeDevice::health(int64_t now_ns) const {
  if (impl_->failed.load(std::memory_order_relaxed)) return DeviceHealth::Failed;
  return impl_->silent(now_ns) ? DeviceHealth::Silent : DeviceHealth::Ok;
}

DeviceCounters UdpBridgeDevice::counters() const {
  const Impl& d = *impl_;
  const auto r = [](const std::atomic<uint64_t>& c) { return c.load(std::memory_order_relaxed); };
  DeviceCounters c;
  c.accepted = r(d.accepted);
  c.malformed = r(d.malformed);
  c.bad_checksum = r(d.bad_checksum);
  c.wrong_version = r(d.wrong_version);
  c.wrong_peer = r(d.wrong_peer);
  c.non_finite = r(d.non_finite);
  c.out_of_workspace = r(d.out_of_workspace);
  c.duplicate = r(d.duplicate);
  c.out_of_order = r(d.out_of_order);
  c.stale = r(d.stale);
  c.clamped = r(d.clamped);
  c.silences = r(d.silences);
  return c;
}

}  // namespace phaco
