#pragma once
// IPv4 UDP endpoints for the bridge and its peer (issue 6 item 4): resolving a host, binding a
// socket. Each throws InputError naming `what` (the device or peer) and the problem. Not for a
// real-time thread (name lookup, system calls).
#include <netinet/in.h>

#include <cstdint>
#include <string>

namespace phaco::udp_socket {

// host:port as an IPv4 address; a host name is resolved once (getaddrinfo, IPv4 only).
sockaddr_in resolve_ipv4(const std::string& host, uint16_t port, const std::string& what);
// A UDP socket bound to host:port (host numeric); returns the fd and the port actually bound.
int bind_udp(const std::string& host, uint16_t port, const std::string& what, uint16_t& bound_port);
bool same_endpoint(const sockaddr_in& a, const sockaddr_in& b);

}  // namespace phaco::udp_socket
