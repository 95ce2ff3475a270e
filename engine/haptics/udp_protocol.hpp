#pragma once
// The UDP bridge's wire format (issue 6 item 4; docs/udp_bridge_protocol.md): fixed 68-byte
// little-endian packets — magic "PHDB", version 1, type, device id, u32 sequence number, sender
// timestamp (µs), payload, CRC-32 (ISO-HDLC, our own table, no zlib). Pure functions over bytes:
// no socket, no clock, no state; safe from any thread.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

namespace phaco {

namespace udp_protocol {

inline constexpr uint32_t kMagic = 0x42444850;  // bytes 'P' 'H' 'D' 'B' read as a LE u32
inline constexpr uint16_t kVersion = 1;
inline constexpr std::size_t kPacketSize = 68;
using Packet = std::array<uint8_t, kPacketSize>;

enum class MessageType : uint8_t { Pose = 1, Force = 2 };

// Peer → device: one device sample.
struct PoseMessage {
  uint32_t device_id = 0;
  uint32_t seq = 0;             // +1 per packet, wraps at 2^32
  uint64_t sender_time_us = 0;  // µs, the sender's monotonic clock (any epoch)
  std::array<float, 3> pos_mm{};
  std::array<float, 4> quat{1, 0, 0, 0};  // w, x, y, z
  float grip = 0;                         // 0..1
  float pedal = 0;                        // 0..3
  uint32_t buttons = 0;
  bool operator==(const PoseMessage&) const = default;
};

// Device → peer: the force to render and which pose sample it was computed from.
struct ForceMessage {
  uint32_t device_id = 0;
  uint32_t seq = 0;             // +1 per force packet
  uint64_t sender_time_us = 0;  // µs, the device side's steady clock
  std::array<float, 3> force_mn{};
  uint32_t ack_seq = 0;             // seq of the newest pose the haptic thread had read
  uint64_t ack_sender_time_us = 0;  // that pose's sender_time_us, echoed: peer-side latency
  uint8_t health = 0;               // DeviceHealth
  bool operator==(const ForceMessage&) const = default;
};

// What decode() found; the device also drops decoded packets for the reasons in DeviceCounters.
enum class DecodeStatus : uint8_t { Ok, Malformed, WrongVersion, BadChecksum, WrongType };

// CRC-32/ISO-HDLC (the zlib/PNG/Ethernet CRC): reflected polynomial 0xEDB88320, init and final
// xor 0xFFFFFFFF. "123456789" → 0xCBF43926.
uint32_t crc32(std::span<const uint8_t> bytes);

Packet encode(const PoseMessage& m);
Packet encode(const ForceMessage& m);
// Checks size, magic, version, CRC and type, in that order (the first failure is returned).
DecodeStatus decode(std::span<const uint8_t> bytes, PoseMessage& out);
DecodeStatus decode(std::span<const uint8_t> bytes, ForceMessage& out);

}  // namespace udp_protocol

}  // namespace phaco
