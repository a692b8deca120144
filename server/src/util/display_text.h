// Text a person chooses and others see (upload file names, display names): cleaned so that it
// shows as what it says. The UI shows it as text, never as HTML; this removes what text itself
// can hide (controls, bidi overrides, invalid UTF-8).
#pragma once

#include <string>
#include <string_view>

namespace brdfa::server {

// `raw` without invalid UTF-8, C0/C1 controls and invisible format characters, trimmed of
// spaces, at most `maxBytes` long (cut before a character that does not fit).
std::string cleanDisplayText(std::string_view raw, size_t maxBytes);

// The current time, ISO 8601 UTC with milliseconds ("2026-12-04T13:28:09.123Z").
std::string nowIso8601();

}  // namespace brdfa::server
