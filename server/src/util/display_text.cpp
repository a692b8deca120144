#include "util/display_text.h"

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <ctime>

namespace brdfa::server {

namespace {

// Length of the valid UTF-8 sequence at s[i] (1..4), or 0 when it is not one.
size_t utf8SequenceLength(std::string_view s, size_t i) {
  const auto byte = [&](size_t k) { return static_cast<unsigned char>(s[k]); };
  const unsigned char c = byte(i);
  size_t n = c < 0x80 ? 1 : (c >> 5) == 0x6 ? 2 : (c >> 4) == 0xE ? 3 : (c >> 3) == 0x1E ? 4 : 0;
  if (n == 0 || i + n > s.size()) return 0;
  for (size_t k = 1; k < n; ++k)
    if ((byte(i + k) & 0xC0) != 0x80) return 0;
  // Overlong forms, surrogates and code points above U+10FFFF.
  if (n == 2 && c < 0xC2) return 0;
  if (n == 3 && ((c == 0xE0 && byte(i + 1) < 0xA0) || (c == 0xED && byte(i + 1) >= 0xA0))) return 0;
  if (n == 4 && ((c == 0xF0 && byte(i + 1) < 0x90) || c > 0xF4 || (c == 0xF4 && byte(i + 1) >= 0x90))) return 0;
  return n;
}

uint32_t codePointAt(std::string_view raw, size_t i, size_t n) {
  const auto byte = [&](size_t k) { return static_cast<unsigned char>(raw[i + k]); };
  if (n == 1) return byte(0);
  uint32_t cp = byte(0) & (0xFFu >> (n + 1));
  for (size_t k = 1; k < n; ++k) cp = (cp << 6) | (byte(k) & 0x3Fu);
  return cp;
}

// Characters a name shown to other users must not carry: C0 and C1 controls, and the
// invisible format characters that reorder or hide text (bidi embeddings, overrides and
// isolates such as U+202E, which can make "gpj.exe" read as "exe.jpg"; zero-width characters;
// the byte order mark; soft hyphen; interlinear annotation; tags).
bool isControlOrFormat(uint32_t cp) {
  return cp < 0x20 || (cp >= 0x7F && cp <= 0x9F) || cp == 0xAD || cp == 0x061C || cp == 0x180E ||
         (cp >= 0x200B && cp <= 0x200F) || (cp >= 0x202A && cp <= 0x202E) || (cp >= 0x2060 && cp <= 0x206F) ||
         cp == 0xFEFF || (cp >= 0xFFF9 && cp <= 0xFFFB) || (cp >= 0xE0000 && cp <= 0xE007F);
}

}  // namespace

std::string cleanDisplayText(std::string_view raw, size_t maxBytes) {
  std::string out;
  for (size_t i = 0; i < raw.size();) {
    size_t n = utf8SequenceLength(raw, i);
    if (n == 0) {  // invalid byte: dropped
      ++i;
      continue;
    }
    if (!isControlOrFormat(codePointAt(raw, i, n))) {
      if (out.size() + n > maxBytes) break;
      out.append(raw.substr(i, n));
    }
    i += n;
  }
  out.erase(0, out.find_first_not_of(' '));
  out.erase(out.find_last_not_of(' ') + 1);
  return out;
}

std::string nowIso8601() {
  using namespace std::chrono;
  const auto now = system_clock::now();
  const std::time_t secs = system_clock::to_time_t(now);
  const long ms = static_cast<long>(duration_cast<milliseconds>(now.time_since_epoch()).count() % 1000);
  std::tm utc{};
  gmtime_r(&secs, &utc);
  char text[64];
  std::snprintf(text, sizeof text, "%04d-%02d-%02dT%02d:%02d:%02d.%03ldZ", utc.tm_year + 1900, utc.tm_mon + 1,
                utc.tm_mday, utc.tm_hour, utc.tm_min, utc.tm_sec, ms);
  return text;
}

}  // namespace brdfa::server
