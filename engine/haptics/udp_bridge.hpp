#pragma once
// A device driven by another process or machine over UDP (issue 6 item 4; seed 001 links its
// tracking machine to the simulation machine the same way). Protocol: docs/udp_bridge_protocol.md
// — fixed 68-byte little-endian packets: magic "PHDB", version 1, type, device id, u32 sequence
// number, sender timestamp (µs), payload, CRC-32 (ISO-HDLC, our own table, no zlib).
//
//   peer ──pose packets──▶ [I/O thread: recvfrom, validate, count] ──seqlock──▶ read()      ┐
//   peer ◀─force packets── [I/O thread: send on change]           ◀──seqlock── write_force() ┘
//                                                                  haptic thread, 1 kHz
//
// The I/O thread owns the socket (poll with a 1 ms timeout); the haptic thread touches only
// atomics: read/write_force/health make no system call other than the clock. The device is
// bound to one configured peer (IPv4 address:port); anything else is dropped and counted.
// Silence (issue 18: frozen and zero force within 5 ms of the last packet): no accepted packet for
// more than silence_timeout_ms (3 ms) → health() says Silent, read() returns the last good pose
// (frozen) and write_force stores zero; the 1 kHz haptic thread sees it at its first tick after
// the timeout (≤ 4 ms after the last packet) and the I/O thread sends the zero within its 1 ms
// poll. Good packets resume it (after a silence any sequence number is accepted, so a restarted
// peer resynchronises).
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>

#include "engine/haptics/device.hpp"
#include "engine/haptics/udp_protocol.hpp"

namespace phaco {

// The wire format (codec): engine/haptics/udp_protocol.hpp.
struct UdpBridgeConfig {
  std::string name = "udp";
  std::string bind_host = "0.0.0.0";    // IPv4 address to listen on
  uint16_t local_port = 0;              // 0: an ephemeral port (see local_port())
  std::string peer_host = "127.0.0.1";  // IPv4 address or host name (resolved once, IPv4)
  uint16_t peer_port = 0;
  uint32_t device_id = 0;  // 0: accept any; else other ids count as wrong_peer
  // No accepted packet for longer → Silent. 3 ms: two lost packets at 1 kHz are ridden through,
  // and the zero force still reaches the peer within 5 ms of the last packet (see above).
  double silence_timeout_ms = 3;
  // A packet is stale when its one-way age exceeds this: age = (receive time − sender time) −
  // the smallest such difference seen (the clock offset plus the base delay), that minimum
  // allowed to rise by 100 µs per s to follow clock drift.
  double max_age_ms = 20;
  DeviceLimits limits{};
};

class UdpBridgeDevice final : public Device {
 public:
  // Opens and binds the socket and resolves the peer; throws InputError naming what failed.
  explicit UdpBridgeDevice(UdpBridgeConfig config);
  ~UdpBridgeDevice() override;

  std::string_view name() const override;
  DeviceLimits limits() const override;
  uint16_t local_port() const;  // the bound port (useful with local_port = 0)

  void start(int64_t now_ns) override;  // starts the I/O thread
  void stop() override;                 // joins it (within ~1 ms)

  bool read(int64_t now_ns, DeviceSample& out) override;
  void write_force(const Vec3& force_mn, int64_t now_ns) override;
  DeviceHealth health(int64_t now_ns) const override;
  DeviceCounters counters() const override;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

// The other end, for tests, tools and the perf harness: sends pose packets (or raw bytes) to a
// device, receives its force packets. Blocking calls; not for a real-time thread.
class UdpBridgePeer {
 public:
  // Binds bind_host:local_port (0 = ephemeral). Throws InputError.
  explicit UdpBridgePeer(uint16_t local_port = 0, const std::string& bind_host = "127.0.0.1");
  ~UdpBridgePeer();
  UdpBridgePeer(const UdpBridgePeer&) = delete;
  UdpBridgePeer& operator=(const UdpBridgePeer&) = delete;

  uint16_t local_port() const { return local_port_; }
  void set_device(const std::string& host, uint16_t port);  // where packets go; throws InputError
  void send(const udp_protocol::PoseMessage& m);
  void send_raw(std::span<const uint8_t> bytes);
  // The next force packet that decodes, waiting at most timeout_ms; nullopt on timeout.
  // Packets that do not decode are skipped.
  std::optional<udp_protocol::ForceMessage> receive_force(double timeout_ms);

 private:
  int fd_ = -1;
  uint16_t local_port_ = 0;
  std::array<uint8_t, 16> device_addr_{};  // a sockaddr_in, kept opaque here
  bool has_device_ = false;
};

// Microseconds on the steady clock, the sender timestamp UdpBridgePeer users normally send.
uint64_t steady_time_us();

}  // namespace phaco
