#include "engine/haptics/device_factory.hpp"

#include <charconv>

#include "engine/core/error.hpp"
#include "engine/haptics/openhaptics_device.hpp"
#include "engine/haptics/replay_device.hpp"
#include "engine/haptics/scripted_device.hpp"
#include "engine/haptics/udp_bridge.hpp"

namespace phaco {

namespace {

constexpr std::string_view kForms =
    "scripted[:left|right], replay:FILE[:left|right], udp:LOCALPORT@PEERHOST:PEERPORT, "
    "openhaptics[:NAME]";

[[noreturn]] void fail(std::string_view text, const std::string& what) {
  throw InputError("device spec '" + std::string(text) + "': " + what);
}

uint16_t parse_port(std::string_view text, std::string_view field, std::string_view spec,
                    bool allow_zero) {
  unsigned value = 0;
  const auto [end, ec] = std::from_chars(field.data(), field.data() + field.size(), value);
  const unsigned lowest = allow_zero ? 0 : 1;
  if (field.empty() || ec != std::errc() || end != field.data() + field.size() || value < lowest ||
      value > 65535) {
    fail(spec, std::string(text) + " '" + std::string(field) + "' is not a port number in " +
                   std::to_string(lowest) + "..65535");
  }
  return static_cast<uint16_t>(value);
}

Hand parse_hand_or_fail(std::string_view name, std::string_view spec) {
  const auto hand = parse_hand(name);
  if (!hand) fail(spec, "unknown hand '" + std::string(name) + "'; expected left or right");
  return *hand;
}

}  // namespace

DeviceSpec parse_device_spec(std::string_view text) {
  if (text.empty()) {
    throw InputError("empty device spec; expected one of: " + std::string(kForms));
  }
  DeviceSpec spec;
  spec.text = std::string(text);
  const std::size_t colon = text.find(':');
  const std::string_view kind = text.substr(0, colon);
  const std::string_view rest =
      colon == std::string_view::npos ? std::string_view() : text.substr(colon + 1);
  const bool has_rest = colon != std::string_view::npos;

  if (kind == "scripted") {
    spec.kind = DeviceKind::Scripted;
    if (has_rest) spec.hand = parse_hand_or_fail(rest, text);
  } else if (kind == "replay") {
    spec.kind = DeviceKind::Replay;
    std::string_view file = rest;
    // A trailing ":left" / ":right" names the hand; any other colon belongs to the path.
    const std::size_t last = rest.rfind(':');
    if (last != std::string_view::npos && parse_hand(rest.substr(last + 1))) {
      spec.hand = parse_hand(rest.substr(last + 1));
      file = rest.substr(0, last);
    }
    if (file.empty()) fail(text, "missing the recording file; expected replay:FILE[:left|right]");
    spec.file = std::filesystem::path(std::string(file));
  } else if (kind == "udp") {
    spec.kind = DeviceKind::Udp;
    const std::size_t at = rest.find('@');
    if (!has_rest || at == std::string_view::npos) {
      fail(text, "expected udp:LOCALPORT@PEERHOST:PEERPORT (e.g. udp:5005@192.168.1.20:5006)");
    }
    spec.local_port = parse_port("local port", rest.substr(0, at), text, true);
    const std::string_view peer = rest.substr(at + 1);
    const std::size_t pc = peer.rfind(':');
    if (pc == std::string_view::npos) {
      fail(text, "peer '" + std::string(peer) + "' has no port; expected PEERHOST:PEERPORT");
    }
    if (pc == 0) fail(text, "peer host is empty; expected PEERHOST:PEERPORT");
    spec.peer_host = std::string(peer.substr(0, pc));
    if (spec.peer_host.find(':') != std::string::npos) {
      fail(text, "peer host '" + spec.peer_host + "' looks like IPv6; only IPv4 is supported");
    }
    spec.peer_port = parse_port("peer port", peer.substr(pc + 1), text, false);
  } else if (kind == "openhaptics") {
    spec.kind = DeviceKind::OpenHaptics;
    if (has_rest && rest.empty()) fail(text, "empty device name after 'openhaptics:'");
    spec.device_name = std::string(rest);
  } else {
    fail(text,
         "unknown device '" + std::string(kind) + "'; expected one of: " + std::string(kForms));
  }
  return spec;
}

std::unique_ptr<Device> make_device(const DeviceSpec& spec, const DeviceContext& context) {
  switch (spec.kind) {
    case DeviceKind::Scripted: {
      const Hand hand = spec.hand.value_or(context.hand);
      if (context.scenario == nullptr) {
        fail(spec.text, "a scripted device needs a scenario to take its track from");
      }
      const HandTrack* track = context.scenario->find_hand(hand);
      if (track == nullptr) {
        fail(spec.text, "scenario '" + context.scenario->source + "' has no " +
                            std::string(to_string(hand)) + " hand to script");
      }
      ScriptedDeviceOptions o;
      o.name = "scripted:" + std::string(to_string(hand));
      return std::make_unique<ScriptedDevice>(*track, o);
    }
    case DeviceKind::Replay: {
      const Scenario recording = load_scenario(spec.file);  // its errors name the file
      const HandTrack* track = nullptr;
      if (spec.hand) {
        track = recording.find_hand(*spec.hand);
        if (track == nullptr) {
          fail(spec.text, "recording '" + spec.file.string() + "' has no " +
                              std::string(to_string(*spec.hand)) + " hand");
        }
      } else if (recording.hands.size() == 1) {
        track = &recording.hands.front();
      } else {
        track = recording.find_hand(context.hand);
        if (track == nullptr) {
          fail(spec.text, "recording '" + spec.file.string() + "' has no " +
                              std::string(to_string(context.hand)) + " hand");
        }
      }
      ReplayDeviceOptions o;
      o.name =
          "replay:" + spec.file.filename().string() + ":" + std::string(to_string(track->hand));
      return std::make_unique<ReplayDevice>(*track, o);
    }
    case DeviceKind::Udp: {
      UdpBridgeConfig c;
      c.name = spec.text;
      c.local_port = spec.local_port;
      c.peer_host = spec.peer_host;
      c.peer_port = spec.peer_port;
      c.silence_timeout_ms = context.silence_timeout_ms;
      return std::make_unique<UdpBridgeDevice>(c);
    }
    case DeviceKind::OpenHaptics: {
#if PHACO_HAVE_OPENHAPTICS
      OpenHapticsOptions o;
      o.device_name = spec.device_name;
      return std::make_unique<OpenHapticsDevice>(o);
#else
      fail(spec.text,
           "this build has no OpenHaptics support (HD/hd.h and libHD were not found when it was "
           "configured)");
#endif
    }
  }
  fail(spec.text, "unknown device kind");
}

}  // namespace phaco
