// The bridge's other end (UdpBridgePeer): for tests, tools and the perf harness.
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "engine/core/clock.hpp"
#include "engine/core/error.hpp"
#include "engine/haptics/udp_bridge.hpp"
#include "engine/haptics/udp_socket.hpp"

namespace phaco {

using namespace udp_protocol;
using udp_socket::bind_udp;
using udp_socket::resolve_ipv4;

uint64_t steady_time_us() {
  return static_cast<uint64_t>(now_ns() / 1000);
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
