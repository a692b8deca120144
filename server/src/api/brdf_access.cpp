#include "api/brdf_access.h"

#include "http/http_errors.h"

namespace brdfa::server {

std::shared_ptr<const BrdfEntry> readableBrdfOr404(Service& service, const Identity& who, const std::string& name,
                                                   httplib::Response& res) {
  if (!isValidQualifiedBrdfName(name)) {
    sendError(res, ErrorCode::InvalidArgument, std::string("BRDF ") + kBrdfNameRule, "name");
    return nullptr;
  }
  auto entry = service.readableBrdf(who, name);
  if (!entry) {
    sendError(res, ErrorCode::NotFound, "no BRDF named '" + name + "'", "name");
    return nullptr;
  }
  return entry;
}

bool mayWriteBrdfName(Service& service, const Identity& who, const std::string& name, httplib::Response& res) {
  if (!isValidQualifiedBrdfName(name)) {
    sendError(res, ErrorCode::InvalidArgument, std::string("BRDF ") + kBrdfNameRule, "name");
    return false;
  }
  const std::string owner(brdfNameOwner(name));
  // Measured uploads are BRDFs under their asset ids (merl_...): a saved file may not shadow one.
  if (std::string_view(name).substr(owner.empty() ? 0 : owner.size() + 1).starts_with("merl_")) {
    sendError(res, ErrorCode::InvalidArgument, "BRDF names starting with merl_ are measured uploads' ids", "name");
    return false;
  }
  if (owner == who.libraryOwner()) return true;
  // A name of a classmate's that one may not read answers as if it were free and unknown.
  if (!owner.empty() && !who.teacher()) {
    auto entry = service.brdfs.find(name);
    auto broken = entry ? std::nullopt : service.brdfs.findBroken(name);
    if (!(entry && canReadBrdf(who, *entry)) && !(broken && canReadBrdf(who, *broken))) {
      sendError(res, ErrorCode::NotFound, "no BRDF named '" + name + "'", "name");
      return false;
    }
  }
  const std::string base = owner.empty() ? name : name.substr(owner.size() + 1);
  sendError(res, ErrorCode::Forbidden,
            who.teacher() ? "BRDF '" + name + "' is " + owner + "'s: the teacher reads and deletes it, only " + owner +
                                " changes it"
                          : "you save BRDFs under your own name: '" + who.brdfNamespace() + base + "'",
            "name");
  return false;
}

}  // namespace brdfa::server
