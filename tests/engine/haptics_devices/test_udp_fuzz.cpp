// Issue 18 item 3: the UDP bridge fuzzed, deterministic by seed (PHACO_UDP_FUZZ_SEED overrides).
//
// 1. The decoder, a pure function: 100,000 random and mutated packets, each with the status its
//    mutation must produce (junk, truncated, oversized, wrong version, flipped bits, bad CRC,
//    wrong type; valid packets carrying NaN, infinite, huge or out-of-range numbers then go
//    through the sample bounds). Every status is checked, not only the absence of a crash.
// 2. The socket path on loopback: 100,000 packets through the real device, good ones in between
//    faults of every kind (also replayed and out-of-order sequence numbers, stale, another peer,
//    another device id). Each packet's expected counter is known when it is made; the device's
//    counters must match them exactly, and after every batch the device's newest sample must be
//    the newest good packet. Batches are small enough for the socket's receive buffer, and each
//    is waited for by its count (no timing is asserted).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "engine/core/clock.hpp"
#include "engine/core/rng.hpp"
#include "engine/haptics/sample_bounds.hpp"
#include "engine/haptics/udp_bridge.hpp"

namespace phaco {
namespace {

using namespace udp_protocol;

constexpr int kPackets = 100'000;  // per part, per run (issue 18: 100,000)

uint64_t fuzz_seed() {
  if (const char* s = std::getenv("PHACO_UDP_FUZZ_SEED")) return std::strtoull(s, nullptr, 10);
  return 18;
}

// Draws for packet i: a counter-based stream, so packet i is the same whatever came before.
struct Draws {
  CounterRng rng;
  uint64_t packet;
  uint32_t next = 0;
  uint32_t u32() { return rng.bits(packet, next++)[0]; }
  uint32_t below(uint32_t n) { return u32() % n; }
  double unit() { return rng.uniform_double(packet, next++); }
  float in(double lo, double hi) { return static_cast<float>(lo + (hi - lo) * unit()); }
};

void put_u32(uint8_t* p, uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<uint8_t>(v >> (8 * i));
}
// A packet whose CRC is right again after a field was changed on purpose.
void reseal(Packet& b) {
  put_u32(&b[64], crc32(std::span<const uint8_t>(b.data(), 64)));
}

PoseMessage good_pose(Draws& d, uint32_t seq) {
  PoseMessage m;
  m.device_id = 7;
  m.seq = seq;
  m.sender_time_us = steady_time_us();
  for (float& x : m.pos_mm) x = d.in(-40, 40);
  m.quat = {d.in(-1, 1), d.in(-1, 1), d.in(-1, 1), 1.0f};  // any length > 0: renormalised
  m.grip = d.in(0, 1);
  m.pedal = d.in(0, 3);
  m.buttons = d.u32();
  return m;
}

// A valid packet whose numbers break the sample bounds; `expect` says how.
PoseMessage bad_numbers(Draws& d, uint32_t seq, SampleCheck& expect) {
  PoseMessage m = good_pose(d, seq);
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  constexpr float kInf = std::numeric_limits<float>::infinity();
  const float sign = d.below(2) ? 1.0f : -1.0f;
  switch (d.below(8)) {
    case 0:
      m.pos_mm[d.below(3)] = kNaN, expect = SampleCheck::NonFinite;
      break;
    case 1:
      m.pos_mm[d.below(3)] = sign * kInf, expect = SampleCheck::NonFinite;
      break;
    case 2:
      m.quat[d.below(4)] = d.below(2) ? kNaN : kInf, expect = SampleCheck::NonFinite;
      break;
    case 3:
      m.quat = {0, 0, 0, 0}, expect = SampleCheck::NonFinite;
      break;
    case 4:
      (d.below(2) ? m.grip : m.pedal) = d.below(2) ? kNaN : -kInf;
      expect = SampleCheck::NonFinite;
      break;
    case 5:  // huge: 50 mm + up to 1e30 (1.2e19 and 1e300-like values broke `phaco run`)
      m.pos_mm[d.below(3)] = sign * static_cast<float>(50.001 * std::pow(10.0, 30 * d.unit()));
      expect = SampleCheck::OutsideWorkspace;
      break;
    case 6:  // finite but no rotation: every component below 1e-7
      for (float& q : m.quat) q = d.in(-1e-7, 1e-7);
      expect = SampleCheck::NonFinite;
      break;
    default:  // grip or pedal out of range: clamped, kept
      m.grip = d.in(1.001, 1e6), m.pedal = -d.in(0.001, 1e6);
      expect = SampleCheck::Clamped;
      break;
  }
  return m;
}

// Faults that the decoder alone catches, as bytes, with the status they must give.
struct Mutant {
  std::vector<uint8_t> bytes;
  DecodeStatus status;
};

Mutant corrupt(Draws& d, const Packet& good) {
  Mutant out{std::vector<uint8_t>(good.begin(), good.end()), DecodeStatus::Malformed};
  std::vector<uint8_t>& b = out.bytes;
  switch (d.below(7)) {
    case 0: {  // junk of any length; never the magic
      b.resize(d.below(200));
      for (uint8_t& x : b) x = static_cast<uint8_t>(d.u32());
      if (b.size() >= 4 && b[0] == 'P' && b[1] == 'H' && b[2] == 'D' && b[3] == 'B') b[0] = 'X';
      break;
    }
    case 1:  // truncated
      b.resize(d.below(kPacketSize));
      break;
    case 2: {  // oversized, also past the device's 2048-byte buffer (MSG_TRUNC)
      const std::size_t extra = 1 + d.below(d.below(8) == 0 ? 2100 : 64);
      for (std::size_t i = 0; i < extra; ++i) b.push_back(static_cast<uint8_t>(d.u32()));
      break;
    }
    case 3: {  // another version, CRC right
      Packet p = good;
      const uint16_t v = static_cast<uint16_t>(2 + d.below(0xFFFE));  // never 1
      p[4] = static_cast<uint8_t>(v), p[5] = static_cast<uint8_t>(v >> 8);
      reseal(p);
      b.assign(p.begin(), p.end());
      out.status = DecodeStatus::WrongVersion;
      break;
    }
    case 4: {  // 1 to 4 flipped bits: CRC-32 catches every such error in 68 bytes (distance 5)
      bool magic = false, version = false;
      const uint32_t flips = 1 + d.below(4);
      uint32_t done[4] = {};
      for (uint32_t k = 0; k < flips; ++k) {
        uint32_t bit;
        bool again;
        do {  // distinct bits, so two flips never cancel
          bit = d.below(kPacketSize * 8);
          again = false;
          for (uint32_t j = 0; j < k; ++j) again |= done[j] == bit;
        } while (again);
        done[k] = bit;
        b[bit / 8] ^= static_cast<uint8_t>(1u << (bit % 8));
        magic |= bit / 8 < 4;
        version |= bit / 8 == 4 || bit / 8 == 5;
      }
      out.status = magic     ? DecodeStatus::Malformed
                   : version ? DecodeStatus::WrongVersion
                             : DecodeStatus::BadChecksum;
      break;
    }
    case 5: {  // the CRC field itself wrong
      const uint32_t right = crc32(std::span<const uint8_t>(b.data(), 64));
      put_u32(&b[64], right ^ (1u + d.below(0xFFFFFFFEu)));
      out.status = DecodeStatus::BadChecksum;
      break;
    }
    default: {  // another type (a force packet, or an unknown one), CRC right
      Packet p = good;
      p[6] = static_cast<uint8_t>(2 + d.below(254));
      reseal(p);
      b.assign(p.begin(), p.end());
      out.status = DecodeStatus::WrongType;
      break;
    }
  }
  return out;
}

// The sample bounds of a decoded pose, as the device applies them.
SampleCheck bounds_of(const PoseMessage& m) {
  DeviceSample s;
  s.pos_mm = Vec3(m.pos_mm[0], m.pos_mm[1], m.pos_mm[2]);
  s.quat = Quat(m.quat[0], m.quat[1], m.quat[2], m.quat[3]);
  s.grip = m.grip, s.pedal = m.pedal;
  return bound_sample(s);
}

const char* name(DecodeStatus s) {
  switch (s) {
    case DecodeStatus::Ok:
      return "ok";
    case DecodeStatus::Malformed:
      return "malformed";
    case DecodeStatus::WrongVersion:
      return "wrong version";
    case DecodeStatus::BadChecksum:
      return "bad checksum";
    case DecodeStatus::WrongType:
      return "wrong type";
  }
  return "?";
}

TEST(UdpFuzz, DecoderGivesEachMutationItsStatus) {
  const uint64_t seed = fuzz_seed();
  const CounterRng rng(seed, /*stream=*/1);
  uint64_t mismatches = 0, by_status[5] = {}, by_bounds[4] = {};
  std::string first;
  for (int i = 0; i < kPackets; ++i) {
    Draws d{rng, static_cast<uint64_t>(i)};
    const PoseMessage m = good_pose(d, d.u32());
    const int kind = static_cast<int>(d.below(4));
    PoseMessage out;
    if (kind == 0) {  // good: decodes to exactly what was sent, within every bound
      const DecodeStatus s = decode(encode(m), out);
      const SampleCheck c = bounds_of(out);
      ++by_status[static_cast<int>(s)], ++by_bounds[static_cast<int>(c)];
      if (s != DecodeStatus::Ok || !(out == m) || c != SampleCheck::Ok) {
        if (mismatches++ == 0) first = "packet " + std::to_string(i) + ": a good packet failed";
      }
    } else if (kind == 1) {  // valid bytes, bad numbers: the decoder passes them, the bounds not
      SampleCheck expect = SampleCheck::Ok;
      const PoseMessage bad = bad_numbers(d, m.seq, expect);
      const DecodeStatus s = decode(encode(bad), out);
      const SampleCheck c = bounds_of(out);
      ++by_status[static_cast<int>(s)], ++by_bounds[static_cast<int>(c)];
      if (s != DecodeStatus::Ok || c != expect) {
        if (mismatches++ == 0)
          first = "packet " + std::to_string(i) + ": bounds gave the wrong check";
      }
    } else {  // corrupted bytes
      const Mutant x = corrupt(d, encode(m));
      const DecodeStatus s = decode(x.bytes, out);
      ++by_status[static_cast<int>(s)];
      if (s != x.status && mismatches++ == 0) {
        first = "packet " + std::to_string(i) + " (" + std::to_string(x.bytes.size()) +
                " bytes): expected " + name(x.status) + ", got " + name(s);
      }
    }
  }
  EXPECT_EQ(mismatches, 0u) << "seed " << seed << "; first: " << first;
  // Every outcome was exercised, so none of the checks above was vacuous.
  for (int s = 0; s < 5; ++s) EXPECT_GT(by_status[s], 1000u) << name(DecodeStatus(s));
  for (int c = 0; c < 4; ++c) EXPECT_GT(by_bounds[c], 1000u) << "sample check " << c;
}

// The device on loopback with a peer and an intruder; silence and staleness set far beyond the
// run (silence has its own test) so that each packet's fate depends on the packet alone.
struct Loopback {
  UdpBridgePeer peer, intruder;
  std::unique_ptr<UdpBridgeDevice> device;
  explicit Loopback(double silence_ms = 600'000) {
    UdpBridgeConfig c;
    c.bind_host = "127.0.0.1";
    c.peer_host = "127.0.0.1";
    c.peer_port = peer.local_port();
    c.device_id = 7;
    c.silence_timeout_ms = silence_ms;
    c.max_age_ms = 5'000;
    device = std::make_unique<UdpBridgeDevice>(c);
    peer.set_device("127.0.0.1", device->local_port());
    intruder.set_device("127.0.0.1", device->local_port());
    device->start(now_ns());
  }
  // Waits (by count) until the device has taken `n` packets in all; false after 10 s without.
  bool wait_seen(uint64_t n) const {
    const int64_t give_up = now_ns() + 10'000'000'000;
    while (device->counters().packets() < n) {
      if (now_ns() > give_up) return false;
      std::this_thread::sleep_for(std::chrono::microseconds(50));
    }
    return true;
  }
};

#define PHACO_EXPECT_COUNTER(field) \
  EXPECT_EQ(got.field, want.field) << #field << " (seed " << seed << ")"

TEST(UdpFuzz, SocketPathCountsEveryBadPacketAndPassesTheGoodOnes) {
  const uint64_t seed = fuzz_seed();
  const CounterRng rng(seed, /*stream=*/2);
  Loopback net;
  DeviceCounters want;
  uint32_t newest = 0;  // the newest accepted seq
  PoseMessage newest_pose;

  // A first good packet, so that replays and reorderings have something to be behind.
  {
    Draws d{rng, 0};
    newest_pose = good_pose(d, newest = 1000);
    net.peer.send(newest_pose);
    ++want.accepted;
    ASSERT_TRUE(net.wait_seen(1));
  }
  // 64 a batch: a 68-byte datagram takes about 1 KiB of the socket's receive buffer and the rare
  // oversized one about 3 KiB, so a batch fits the default 208 KiB with room to spare and the
  // kernel never drops one before the device has counted it.
  constexpr int kBatch = 64;
  uint64_t sent = 1, batches_checked = 0, sample_mismatches = 0;
  for (int i = 1; i < kPackets; ++i) {
    Draws d{rng, static_cast<uint64_t>(i)};
    const uint32_t kind = d.below(16);
    if (kind < 4) {                                                 // good
      const PoseMessage m = good_pose(d, newest + 1 + d.below(3));  // lost packets are no error
      net.peer.send(m);
      newest = m.seq, newest_pose = m;
      ++want.accepted;
    } else if (kind < 8) {  // bytes the decoder rejects
      const Mutant x = corrupt(d, encode(good_pose(d, newest + 1)));
      net.peer.send_raw(x.bytes);
      switch (x.status) {
        case DecodeStatus::WrongVersion:
          ++want.wrong_version;
          break;
        case DecodeStatus::BadChecksum:
          ++want.bad_checksum;
          break;
        default:  // malformed, wrong type
          ++want.malformed;
          break;
      }
    } else if (kind < 10) {  // valid packets with bad numbers
      SampleCheck expect = SampleCheck::Ok;
      const PoseMessage m = bad_numbers(d, newest + 1, expect);
      net.peer.send(m);
      if (expect == SampleCheck::NonFinite) ++want.non_finite;
      if (expect == SampleCheck::OutsideWorkspace) ++want.out_of_workspace;
      if (expect == SampleCheck::Clamped) {  // kept, with grip and pedal clamped
        ++want.accepted, ++want.clamped;
        newest = m.seq, newest_pose = m;
        newest_pose.grip = 1.0f, newest_pose.pedal = 0.0f;
      }
    } else if (kind == 10) {  // replayed: the newest again
      PoseMessage m = good_pose(d, newest);
      net.peer.send(m);
      ++want.duplicate;
    } else if (kind == 11) {  // out of order: behind the newest, by up to 2^31 − 1
      const uint32_t behind = 1 + (d.below(2) ? d.below(64) : d.below(0x7FFFFFFFu));
      net.peer.send(good_pose(d, newest - behind));
      ++want.out_of_order;
    } else if (kind == 12) {  // stale: sent 2 min ago (the clock offset is learnt from the good)
      PoseMessage m = good_pose(d, newest + 1);
      m.sender_time_us -= 120'000'000;
      net.peer.send(m);
      ++want.stale;
    } else if (kind == 13) {  // another device id
      PoseMessage m = good_pose(d, newest + 1);
      m.device_id = 8 + d.below(1000);
      net.peer.send(m);
      ++want.wrong_peer;
    } else {  // another address:port, good bytes or bad
      if (d.below(2)) {
        net.intruder.send(good_pose(d, newest + 1));
      } else {
        net.intruder.send_raw(corrupt(d, encode(good_pose(d, newest + 1))).bytes);
      }
      ++want.wrong_peer;
    }
    ++sent;
    if (sent % kBatch == 0 || i + 1 == kPackets) {
      ASSERT_TRUE(net.wait_seen(sent))
          << "the device took " << net.device->counters().packets() << " of " << sent
          << " packets within 10 s (seed " << seed << ")";
      // Good packets get through: the newest sample is the newest good packet, whatever
      // came after it.
      DeviceSample s;
      const bool got = net.device->read(now_ns(), s);
      const Vec3 pos(newest_pose.pos_mm[0], newest_pose.pos_mm[1], newest_pose.pos_mm[2]);
      if (!got || s.seq != newest || s.pos_mm != pos ||
          s.grip != static_cast<double>(newest_pose.grip) ||
          s.pedal != static_cast<double>(newest_pose.pedal)) {
        ++sample_mismatches;
      }
      ++batches_checked;
    }
  }
  net.device->stop();
  const DeviceCounters got = net.device->counters();
  EXPECT_EQ(got.packets(), sent);
  EXPECT_EQ(sample_mismatches, 0u) << "of " << batches_checked << " batches (seed " << seed << ")";
  PHACO_EXPECT_COUNTER(accepted);
  PHACO_EXPECT_COUNTER(malformed);
  PHACO_EXPECT_COUNTER(bad_checksum);
  PHACO_EXPECT_COUNTER(wrong_version);
  PHACO_EXPECT_COUNTER(wrong_peer);
  PHACO_EXPECT_COUNTER(non_finite);
  PHACO_EXPECT_COUNTER(out_of_workspace);
  PHACO_EXPECT_COUNTER(duplicate);
  PHACO_EXPECT_COUNTER(out_of_order);
  PHACO_EXPECT_COUNTER(stale);
  PHACO_EXPECT_COUNTER(clamped);
  EXPECT_EQ(got.silences, 0u);
  // Every reason was exercised.
  for (uint64_t n :
       {want.malformed, want.bad_checksum, want.wrong_version, want.wrong_peer, want.non_finite,
        want.out_of_workspace, want.duplicate, want.out_of_order, want.stale, want.clamped}) {
    EXPECT_GT(n, 1000u);
  }
  EXPECT_GT(want.accepted, 20'000u);
}

#undef PHACO_EXPECT_COUNTER

// Valid packets whose sender time is anything at all (0, 2^63, 2^64 − 1, random, near ours): the
// staleness arithmetic, modular differences between two clocks of any epochs, must not overflow
// (UBSan checks that in CI) and no packet may vanish: each is accepted or stale, nothing else.
// Which of the two depends on the times before it, so only the sum is checked; then the device
// must still be usable: once silent, a good packet is accepted again.
TEST(UdpFuzz, AnySenderTimeIsAcceptedOrStaleAndTheDeviceRecovers) {
  const uint64_t seed = fuzz_seed();
  const CounterRng rng(seed, /*stream=*/3);
  Loopback net(/*silence_ms=*/20);
  constexpr int kTimes = 20'000, kBatch = 64;
  uint32_t seq = 0;
  for (int i = 0; i < kTimes; ++i) {
    Draws d{rng, static_cast<uint64_t>(i)};
    PoseMessage m = good_pose(d, ++seq);
    switch (d.below(8)) {
      case 0:
        m.sender_time_us = 0;
        break;
      case 1:
        m.sender_time_us = ~uint64_t{0};
        break;
      case 2:
        m.sender_time_us = uint64_t{1} << 63;
        break;
      case 3:
        m.sender_time_us = (uint64_t{1} << 63) - 1;
        break;
      case 4:  // near ours, up to ±2^40 µs (12 days) off
        m.sender_time_us += (uint64_t{d.u32()} << 8) - (uint64_t{1} << 39);
        break;
      default:
        m.sender_time_us = (uint64_t{d.u32()} << 32) | d.u32();
        break;
    }
    net.peer.send(m);
    if ((i + 1) % kBatch == 0 || i + 1 == kTimes) {
      ASSERT_TRUE(net.wait_seen(static_cast<uint64_t>(i) + 1)) << "seed " << seed;
    }
  }
  DeviceCounters c = net.device->counters();
  EXPECT_EQ(c.accepted + c.stale, static_cast<uint64_t>(kTimes)) << "seed " << seed;
  EXPECT_EQ(c.packets(), static_cast<uint64_t>(kTimes));
  EXPECT_GT(c.stale, 0u) << "the times were wild enough to make some stale";

  // Silent (by the device's own clock), then a good packet: resynchronised and accepted.
  const int64_t give_up = now_ns() + 10'000'000'000;
  while (net.device->health(now_ns()) != DeviceHealth::Silent && now_ns() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  ASSERT_EQ(net.device->health(now_ns()), DeviceHealth::Silent);
  Draws d{rng, kTimes};
  net.peer.send(good_pose(d, ++seq));
  ASSERT_TRUE(net.wait_seen(static_cast<uint64_t>(kTimes) + 1));
  EXPECT_EQ(net.device->counters().accepted, c.accepted + 1)
      << "after a silence the first good packet is accepted, whatever the times before it";
  net.device->stop();
}

}  // namespace
}  // namespace phaco
