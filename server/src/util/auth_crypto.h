// The few primitives of OpenSSL's libcrypto the server uses: for identities random secrets,
// their SHA-256 for storage and a comparison whose time does not depend on where two secrets
// differ; base64 for data URLs.
#pragma once

#include <string>
#include <string_view>

namespace brdfa::server {

// `bytes` random bytes from the OS's generator, base64url without padding; "" when the
// generator fails (callers refuse to make a secret then).
std::string randomBase64Url(size_t bytes);

// `length` characters of [a-z0-9], uniformly (rejection sampling); "" on failure.
std::string randomLowerAlnum(size_t length);

// SHA-256 of `text` as 64 lower-case hex digits.
std::string sha256Hex(std::string_view text);

// True when a and b are equal; for equal lengths the time does not depend on their content.
bool constantTimeEqual(std::string_view a, std::string_view b);

// Standard base64 (RFC 4648, with padding) of `bytes`.
std::string base64Encode(std::string_view bytes);

}  // namespace brdfa::server
