#include "util/address_range.h"

#include <arpa/inet.h>

#include <cstdlib>
#include <cstring>

namespace brdfa::server {

namespace {

// 16 bytes of an IPv6 address, or an IPv4 one mapped (::ffff:a.b.c.d); false when neither.
bool parseAddress(const std::string& text, std::array<unsigned char, 16>& out, bool& v4) {
  in_addr a4{};
  v4 = inet_pton(AF_INET, text.c_str(), &a4) == 1;
  if (v4) {
    out.fill(0);
    out[10] = out[11] = 0xff;
    std::memcpy(out.data() + 12, &a4, 4);
    return true;
  }
  in6_addr a6{};
  if (inet_pton(AF_INET6, text.c_str(), &a6) != 1) return false;
  std::memcpy(out.data(), &a6, 16);
  return true;
}

}  // namespace

bool AddressRange::contains(const std::string& address) const {
  std::array<unsigned char, 16> a{};
  bool v4 = false;
  if (!parseAddress(address, a, v4)) return false;
  int left = bits;
  for (size_t i = 0; i < 16 && left > 0; ++i, left -= 8) {
    const unsigned char mask = left >= 8 ? 0xff : static_cast<unsigned char>(0xff << (8 - left));
    if ((a[i] & mask) != (base[i] & mask)) return false;
  }
  return true;
}

std::optional<AddressRange> parseAddressRange(const std::string& text) {
  const size_t slash = text.find('/');
  AddressRange range;
  bool v4 = false;
  if (!parseAddress(text.substr(0, slash), range.base, v4)) return std::nullopt;
  range.bits = 128;
  if (slash != std::string::npos) {
    const std::string b = text.substr(slash + 1);
    char* end = nullptr;
    const long n = std::strtol(b.c_str(), &end, 10);
    const long most = v4 ? 32 : 128;
    if (b.empty() || *end != '\0' || n < 0 || n > most) return std::nullopt;
    range.bits = static_cast<int>(v4 ? n + 96 : n);
  }
  return range;
}

}  // namespace brdfa::server
