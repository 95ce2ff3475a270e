#pragma once
// Devices from a one-line spec (command line, config):
//   scripted[:left|right]                the scenario's track for that hand (default: context's)
//   replay:FILE[:left|right]             a recording (a scenario file); hand optional when the
//                                        file has one hand
//   udp:LOCALPORT@PEERHOST:PEERPORT      the UDP bridge (docs/udp_bridge_protocol.md); LOCALPORT 0
//                                        = ephemeral; PEERHOST an IPv4 address or host name
//   openhaptics[:NAME]                   OpenHaptics device NAME (default device when omitted)
// Bad specs throw InputError with a message naming the spec and what was wrong.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "engine/haptics/device.hpp"
#include "engine/io/scenario.hpp"

namespace phaco {

enum class DeviceKind : uint8_t { Scripted, Replay, Udp, OpenHaptics };

struct DeviceSpec {
  DeviceKind kind = DeviceKind::Scripted;
  std::string text;            // as given, for messages
  std::optional<Hand> hand;    // scripted, replay
  std::filesystem::path file;  // replay
  uint16_t local_port = 0;     // udp
  std::string peer_host;       // udp
  uint16_t peer_port = 0;      // udp
  std::string device_name;     // openhaptics
};

// What a spec may need from the run: the scenario (scripted) and the hand to drive.
struct DeviceContext {
  const Scenario* scenario = nullptr;
  Hand hand = Hand::Right;
  double silence_timeout_ms = 3;  // udp: UdpBridgeConfig's default, see udp_bridge.hpp
};

DeviceSpec parse_device_spec(std::string_view text);  // throws InputError
std::unique_ptr<Device> make_device(const DeviceSpec& spec, const DeviceContext& context = {});
inline std::unique_ptr<Device> make_device(std::string_view text,
                                           const DeviceContext& context = {}) {
  return make_device(parse_device_spec(text), context);
}

}  // namespace phaco
