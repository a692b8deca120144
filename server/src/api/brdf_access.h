// How the BRDF and preset routes find what a request names, with the ownership rules applied
// (docs/api.md, Library namespaces): one place for "someone else's is 404, readable but not
// yours is 403".
#pragma once

#include <httplib.h>

#include <memory>
#include <string>

#include "service/service.h"

namespace brdfa::server {

inline constexpr const char* kBrdfNameRule =
    "names are [<user>/]<name>: <name> 1-64 characters of [A-Za-z0-9_-], not 'inline', 'validate' or 'presets'";
// A path's BRDF name: a bare or qualified name, then optionally /presets[/<preset>].
inline constexpr const char* kBrdfPathName = "([^/]+(?:/[^/]+)?)";

// The BRDF `name` as `who` may read it, or answers 400 (bad name) / 404 (none, or not theirs
// to read) and returns null.
std::shared_ptr<const BrdfEntry> readableBrdfOr404(Service& service, const Identity& who, const std::string& name,
                                                   httplib::Response& res);

// Whether `who` may store a BRDF under `name`; else answers (400 bad name, 403 naming where
// they may save, 404 for a classmate's unshared name) and returns false.
bool mayWriteBrdfName(Service& service, const Identity& who, const std::string& name, httplib::Response& res);

}  // namespace brdfa::server
