// Client address ranges (--proxy-from): which peers a header of theirs is trusted from.
#pragma once

#include <array>
#include <optional>
#include <string>

namespace brdfa::server {

// An address range of --proxy-from: IPv4 addresses are kept as IPv4-mapped IPv6.
struct AddressRange {
  std::array<unsigned char, 16> base{};
  int bits = 128;
  bool contains(const std::string& address) const;
};
// "ADDR" or "ADDR/BITS", IPv4 or IPv6; nullopt when it is neither.
std::optional<AddressRange> parseAddressRange(const std::string& text);

}  // namespace brdfa::server
