// One file for now: codec, CRC, seqlock, sockets and the I/O thread of one device; issue 22 splits
// the codec from the transport.
#include "engine/haptics/udp_bridge.hpp"

#include <arpa/inet.h>
#include <netdb.h>
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
#include <type_traits>

#include "engine/core/clock.hpp"
#include "engine/core/error.hpp"
#include "engine/haptics/sample_bounds.hpp"

namespace phaco {

// ---------------------------------------------------------------------------------------------
// Protocol
// ---------------------------------------------------------------------------------------------
namespace udp_protocol {

namespace {

// Byte offsets (docs/udp_bridge_protocol.md). Common header, then the payload, then the CRC.
constexpr std::size_t kOffMagic = 0, kOffVersion = 4, kOffType = 6, kOffDeviceId = 8, kOffSeq = 12,
                      kOffTime = 16, kOffPayload = 24, kOffCrc = 64;

constexpr std::array<uint32_t, 256> make_crc_table() {
  std::array<uint32_t, 256> t{};
  for (uint32_t i = 0; i < 256; ++i) {
    uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    t[i] = c;
  }
  return t;
}
constexpr std::array<uint32_t, 256> kCrcTable = make_crc_table();

// Little-endian field access, byte by byte so that it is right on any host.
template <typename U>
void put(uint8_t* p, U v) {
  static_assert(std::is_unsigned_v<U>);
  for (std::size_t i = 0; i < sizeof(U); ++i) p[i] = static_cast<uint8_t>(v >> (8 * i));
}
template <typename U>
U get(const uint8_t* p) {
  U v = 0;
  for (std::size_t i = 0; i < sizeof(U); ++i) v |= static_cast<U>(static_cast<U>(p[i]) << (8 * i));
  return v;
}
void put_f32(uint8_t* p, float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  put(p, u);
}
float get_f32(const uint8_t* p) {
  const uint32_t u = get<uint32_t>(p);
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}

void put_header(Packet& b, MessageType type, uint32_t device_id, uint32_t seq, uint64_t time_us) {
  put(&b[kOffMagic], kMagic);
  put(&b[kOffVersion], kVersion);
  b[kOffType] = static_cast<uint8_t>(type);
  b[kOffType + 1] = 0;  // flags, reserved
  put(&b[kOffDeviceId], device_id);
  put(&b[kOffSeq], seq);
  put(&b[kOffTime], time_us);
}

void seal(Packet& b) {
  put(&b[kOffCrc], crc32(std::span<const uint8_t>(b.data(), kOffCrc)));
}

DecodeStatus check(std::span<const uint8_t> bytes, MessageType type) {
  // Version before size, so that a future version with another size is reported as a version
  // mismatch rather than as garbage.
  if (bytes.size() < kOffVersion + 2) return DecodeStatus::Malformed;
  if (get<uint32_t>(&bytes[kOffMagic]) != kMagic) return DecodeStatus::Malformed;
  if (get<uint16_t>(&bytes[kOffVersion]) != kVersion) return DecodeStatus::WrongVersion;
  if (bytes.size() != kPacketSize) return DecodeStatus::Malformed;
  if (get<uint32_t>(&bytes[kOffCrc]) != crc32(bytes.first(kOffCrc))) {
    return DecodeStatus::BadChecksum;
  }
  if (bytes[kOffType] != static_cast<uint8_t>(type)) return DecodeStatus::WrongType;
  return DecodeStatus::Ok;
}

}  // namespace

uint32_t crc32(std::span<const uint8_t> bytes) {
  uint32_t c = 0xFFFFFFFFu;
  for (const uint8_t x : bytes) c = kCrcTable[(c ^ x) & 0xFFu] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}

Packet encode(const PoseMessage& m) {
  Packet b{};
  put_header(b, MessageType::Pose, m.device_id, m.seq, m.sender_time_us);
  uint8_t* p = &b[kOffPayload];
  for (int i = 0; i < 3; ++i) put_f32(p + 4 * i, m.pos_mm[i]);     // 24..35
  for (int i = 0; i < 4; ++i) put_f32(p + 12 + 4 * i, m.quat[i]);  // 36..51
  put_f32(p + 28, m.grip);                                         // 52
  put_f32(p + 32, m.pedal);                                        // 56
  put(p + 36, m.buttons);                                          // 60
  seal(b);
  return b;
}

Packet encode(const ForceMessage& m) {
  Packet b{};
  put_header(b, MessageType::Force, m.device_id, m.seq, m.sender_time_us);
  uint8_t* p = &b[kOffPayload];
  for (int i = 0; i < 3; ++i) put_f32(p + 4 * i, m.force_mn[i]);  // 24..35
  put(p + 12, m.ack_seq);                                         // 36
  put(p + 16, m.ack_sender_time_us);                              // 40
  p[24] = m.health;                                               // 48; 49..63 reserved, zero
  seal(b);
  return b;
}

DecodeStatus decode(std::span<const uint8_t> bytes, PoseMessage& out) {
  const DecodeStatus s = check(bytes, MessageType::Pose);
  if (s != DecodeStatus::Ok) return s;
  const uint8_t* p = &bytes[kOffPayload];
  out.device_id = get<uint32_t>(&bytes[kOffDeviceId]);
  out.seq = get<uint32_t>(&bytes[kOffSeq]);
  out.sender_time_us = get<uint64_t>(&bytes[kOffTime]);
  for (int i = 0; i < 3; ++i) out.pos_mm[i] = get_f32(p + 4 * i);
  for (int i = 0; i < 4; ++i) out.quat[i] = get_f32(p + 12 + 4 * i);
  out.grip = get_f32(p + 28);
  out.pedal = get_f32(p + 32);
  out.buttons = get<uint32_t>(p + 36);
  return DecodeStatus::Ok;
}

DecodeStatus decode(std::span<const uint8_t> bytes, ForceMessage& out) {
  const DecodeStatus s = check(bytes, MessageType::Force);
  if (s != DecodeStatus::Ok) return s;
  const uint8_t* p = &bytes[kOffPayload];
  out.device_id = get<uint32_t>(&bytes[kOffDeviceId]);
  out.seq = get<uint32_t>(&bytes[kOffSeq]);
  out.sender_time_us = get<uint64_t>(&bytes[kOffTime]);
  for (int i = 0; i < 3; ++i) out.force_mn[i] = get_f32(p + 4 * i);
  out.ack_seq = get<uint32_t>(p + 12);
  out.ack_sender_time_us = get<uint64_t>(p + 16);
  out.health = p[24];
  return DecodeStatus::Ok;
}

}  // namespace udp_protocol

uint64_t steady_time_us() {
  return static_cast<uint64_t>(now_ns() / 1000);
}

namespace {

using namespace udp_protocol;

// Single writer, single reader, the value copied through atomic words so that a torn read is a
// detected retry rather than a data race (and ThreadSanitizer agrees). The reader never waits: it
// tries a few times and otherwise keeps what it had; the writer holds the odd count for ~20 ns.
template <typename T>
class Seqlock {
  static_assert(std::is_trivially_copyable_v<T>);
  static constexpr std::size_t kWords = (sizeof(T) + 7) / 8;

 public:
  void store(const T& v) noexcept {
    uint64_t w[kWords] = {};
    std::memcpy(w, &v, sizeof(T));
    // Relaxed: this thread is the only writer of seq_.
    const uint32_t s = seq_.load(std::memory_order_relaxed);
    seq_.store(s + 1, std::memory_order_relaxed);
    // Release fence: the odd count is visible before any new word is.
    std::atomic_thread_fence(std::memory_order_release);
    // Relaxed: ordered by the fence above and the release store below.
    for (std::size_t i = 0; i < kWords; ++i) words_[i].store(w[i], std::memory_order_relaxed);
    // Release: the words are visible before the even count that vouches for them.
    seq_.store(s + 2, std::memory_order_release);
  }

  bool load(T& out) const noexcept {
    for (int attempt = 0; attempt < 4; ++attempt) {
      // Acquire: pairs with the writer's final release store; the words read below are at least
      // as new as this count.
      const uint32_t s0 = seq_.load(std::memory_order_acquire);
      if (s0 == 0) return false;  // never written
      if (s0 & 1u) continue;      // a write in progress
      uint64_t w[kWords];
      // Relaxed: validated by the count re-check below.
      for (std::size_t i = 0; i < kWords; ++i) w[i] = words_[i].load(std::memory_order_relaxed);
      // Acquire fence: the word loads complete before the re-check (pairs with the writer's
      // release fence).
      std::atomic_thread_fence(std::memory_order_acquire);
      // Relaxed: ordered by the fence above.
      if (seq_.load(std::memory_order_relaxed) == s0) {
        std::memcpy(&out, w, sizeof(T));
        return true;
      }
    }
    return false;
  }

  // Changes on every store. Acquire: a reader that sees a new version then loads the new value.
  uint32_t version() const noexcept { return seq_.load(std::memory_order_acquire); }

 private:
  std::atomic<uint32_t> seq_{0};
  std::array<std::atomic<uint64_t>, kWords> words_{};
};

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

sockaddr_in resolve_ipv4(const std::string& host, uint16_t port, const std::string& what) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  if (inet_pton(AF_INET, host.c_str(), &a.sin_addr) == 1) return a;
  addrinfo hints{};
  hints.ai_family = AF_INET;
  hints.ai_socktype = SOCK_DGRAM;
  addrinfo* res = nullptr;
  const int rc = getaddrinfo(host.c_str(), nullptr, &hints, &res);
  if (rc != 0 || res == nullptr) {
    throw InputError(what + ": cannot resolve host '" + host +
                     "' to an IPv4 address: " + (rc != 0 ? gai_strerror(rc) : "no address"));
  }
  a.sin_addr = reinterpret_cast<const sockaddr_in*>(res->ai_addr)->sin_addr;
  freeaddrinfo(res);
  return a;
}

// A UDP socket bound to host:port; returns the fd and the port actually bound.
int bind_udp(const std::string& host, uint16_t port, const std::string& what,
             uint16_t& bound_port) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  if (inet_pton(AF_INET, host.c_str(), &a.sin_addr) != 1) {
    throw InputError(what + ": bind address '" + host +
                     "' is not a numeric IPv4 address (e.g. 0.0.0.0 or 127.0.0.1)");
  }
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) throw InputError(what + ": cannot create a UDP socket: " + std::strerror(errno));
  if (::bind(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0) {
    const int e = errno;
    ::close(fd);
    throw InputError(what + ": cannot bind UDP " + host + ":" + std::to_string(port) + ": " +
                     std::strerror(e));
  }
  socklen_t len = sizeof a;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  bound_port = ntohs(a.sin_port);
  return fd;
}

bool same_endpoint(const sockaddr_in& a, const sockaddr_in& b) {
  return a.sin_addr.s_addr == b.sin_addr.s_addr && a.sin_port == b.sin_port;
}

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

// ---------------------------------------------------------------------------------------------
// The peer
// ---------------------------------------------------------------------------------------------
UdpBridgePeer::UdpBridgePeer(uint16_t local_port, const std::string& bind_host) {
  fd_ = bind_udp(bind_host, local_port, "udp peer", local_port_);
}

UdpBridgePeer::~UdpBridgePeer() {
  if (fd_ >= 0) ::close(fd_);
}

void UdpBridgePeer::set_device(const std::string& host, uint16_t port) {
  const sockaddr_in a = resolve_ipv4(host, port, "udp peer: device");
  static_assert(sizeof a == sizeof device_addr_);
  std::memcpy(device_addr_.data(), &a, sizeof a);
  has_device_ = true;
}

void UdpBridgePeer::send_raw(std::span<const uint8_t> bytes) {
  if (!has_device_) throw InputError("udp peer: set_device() before sending");
  const ssize_t n =
      ::sendto(fd_, bytes.data(), bytes.size(), 0,
               reinterpret_cast<const sockaddr*>(device_addr_.data()), sizeof(sockaddr_in));
  if (n < 0) throw InputError(std::string("udp peer: send failed: ") + std::strerror(errno));
}

void UdpBridgePeer::send(const PoseMessage& m) {
  const Packet b = encode(m);
  send_raw(b);
}

std::optional<ForceMessage> UdpBridgePeer::receive_force(double timeout_ms) {
  const int64_t deadline = now_ns() + std::llround(timeout_ms * 1e6);
  std::array<uint8_t, 2048> buf{};
  for (;;) {
    const int64_t left_ms = (deadline - now_ns() + 999'999) / 1'000'000;
    if (left_ms <= 0) return std::nullopt;
    pollfd pfd{fd_, POLLIN, 0};
    if (::poll(&pfd, 1, static_cast<int>(left_ms)) <= 0) continue;
    const ssize_t n = ::recv(fd_, buf.data(), buf.size(), MSG_DONTWAIT);
    if (n <= 0) continue;
    ForceMessage m;
    if (decode(std::span<const uint8_t>(buf.data(), static_cast<std::size_t>(n)), m) ==
        DecodeStatus::Ok) {
      return m;
    }
  }
}

}  // namespace phaco
