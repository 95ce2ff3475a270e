#include "engine/haptics/udp_protocol.hpp"

#include <cstring>

namespace phaco {

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

}  // namespace phaco
