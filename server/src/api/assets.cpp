// Assets: POST /api/assets (multipart upload), GET /api/assets[?kind=],
// GET /api/assets/{id}, DELETE /api/assets/{id}. Validation and storage live in AssetStore; this file reads the
// multipart body without holding more than one file's worth of it.
#include <algorithm>

#include "api/routes.h"
#include "http/http_errors.h"
#include "storage/asset_store.h"

namespace brdfa::server {

namespace {

constexpr size_t kMaxFormFieldBytes = 256;  // the `kind` field, and anything else sent
constexpr size_t kMaxFormParts = 16;

struct FormPart {
  std::string name, fileName, contentType;
  std::string content;  // at most the part's cap
  uint64_t size = 0;    // everything the client sent in it
};

// Reads the whole body (so the connection stays usable whatever the answer), keeping at most
// `fileCap` bytes of each `file` part and kMaxFormFieldBytes of other parts. False when the body
// is not valid multipart/form-data or exceeds the payload limit (res.status says which).
// A `file` part's buffer is sized once for `bodyBytes` (the memory already held for the body):
// grown by appends, a large file would be copied again at every doubling.
bool readForm(const httplib::ContentReader& reader, uint64_t fileCap, uint64_t bodyBytes, std::vector<FormPart>& parts,
              size_t& extraParts) {
  return reader(
      [&](const httplib::MultipartFormData& header) {
        if (parts.size() >= kMaxFormParts) {
          ++extraParts;
          return true;
        }
        parts.push_back({header.name, header.filename, header.content_type, {}, 0});
        if (header.name == "file") parts.back().content.reserve(std::min(fileCap, bodyBytes));
        return true;
      },
      [&](const char* data, size_t length) {
        if (parts.empty() || extraParts > 0) return true;  // a part past the cap: drained, not kept
        FormPart& p = parts.back();
        const uint64_t cap = p.name == "file" ? fileCap : kMaxFormFieldBytes;
        if (p.content.size() < cap) p.content.append(data, std::min<uint64_t>(length, cap - p.content.size()));
        p.size += length;
        return true;
      });
}

// An upload refusal: the usual error body plus `reason` (assetRejectionName).
void sendRejection(httplib::Response& res, const Error& error, AssetRejection reason) {
  // The store's Error says what went wrong; these two rejections answer under codes of their own.
  ErrorCode code = error.code;
  if (reason == AssetRejection::StorageFull) code = ErrorCode::StorageFull;
  if (reason == AssetRejection::Busy) code = ErrorCode::Busy;
  nlohmann::json body{
      {"error", errorCodeName(code)}, {"message", error.message}, {"reason", assetRejectionName(reason)}};
  if (!error.field.empty() && code == error.code) body["field"] = error.field;
  sendJson(res, body, errorHttpStatus(code));
}

void badUpload(httplib::Response& res, const std::string& message, const std::string& field = "file") {
  sendError(res, ErrorCode::InvalidArgument, message, field);
}

// Built-ins, Blender worlds and the course's uploads are everyone's; an upload, its uploader's.
bool assetReadable(const Identity& who, const AssetRecord& r) { return canRead(who, r.owner, r.owner.empty()); }

}  // namespace

namespace {

void uploadAsset(Service& service, const httplib::Request& req, httplib::Response& res,
                 const httplib::ContentReader& reader) {
  if (!req.is_multipart_form_data()) {
    reader([](const char*, size_t) { return true; });  // drain: the answer does not need it
    return badUpload(res, "an upload is multipart/form-data with a `file` part (and optionally `kind`)");
  }
  // The body's bytes are held until the upload is stored: they count against the uploads' share
  // of --max-memory from before the first is read (the largest body when the length is not
  // given up front).
  uint64_t length = service.maxRequestBody();
  if (req.has_header("Content-Length"))
    length = std::min<uint64_t>(length, std::strtoull(req.get_header_value("Content-Length").c_str(), nullptr, 10));
  RenderSlots& memory = *service.uploadMemory;
  // Read and dropped: a client still sending would not see the answer.
  auto drain = [&] {
    reader([](const httplib::MultipartFormData&) { return true; }, [](const char*, size_t) { return true; });
  };
  if (length > memory.capacity()) {
    drain();
    return sendError(res, ErrorCode::OverBudget,
                     "an upload of " + std::to_string(length >> 20) + " MiB does not fit the uploads' share (" +
                         std::to_string(memory.capacity() >> 20) +
                         " MiB, an eighth) of the server's memory budget "
                         "(--max-memory " +
                         std::to_string(service.memoryBudgetBytes >> 20) + " MiB)");
  }
  if (!memory.acquire(kUploadMemoryWait, length)) {
    drain();
    res.set_header("Retry-After", "1");
    return sendError(res, ErrorCode::Busy,
                     "other uploads in flight hold the uploads' share of the memory budget; try again");
  }
  struct Held {
    RenderSlots& slots;
    uint64_t bytes;
    ~Held() { slots.release(bytes); }
  } held{memory, length};
  // One byte past the limit is enough to know a file is too large; its full size is counted.
  std::vector<FormPart> parts;
  size_t extraParts = 0;
  if (!readForm(reader, service.config.maxUploadBytes + 1, length, parts, extraParts)) {
    if (res.status == 413)
      return sendError(res, ErrorCode::PayloadTooLarge,
                       "the request body is larger than " + std::to_string(service.maxRequestBody()) +
                           " bytes (--max-upload-bytes " + std::to_string(service.config.maxUploadBytes) +
                           " plus room for the multipart framing)");
    return badUpload(res, "the body is not valid multipart/form-data", "body");
  }
  if (extraParts > 0)
    return badUpload(res, "too many form parts (at most " + std::to_string(kMaxFormParts) + ")", "body");

  const FormPart* file = nullptr;
  const FormPart* kind = nullptr;
  for (const FormPart& p : parts) {
    const FormPart** slot = p.name == "file" ? &file : p.name == "kind" ? &kind : nullptr;
    if (!slot)
      return badUpload(res, "unknown form field '" + p.name.substr(0, 64) + "' (expected file, kind)",
                       p.name.substr(0, 64));
    if (*slot) return badUpload(res, "more than one `" + p.name + "` part", p.name);
    *slot = &p;
  }
  if (!file) return badUpload(res, "no `file` part: send the asset as the form field `file`");
  if (kind && kind->size > kMaxFormFieldBytes) return badUpload(res, "the `kind` field is too long", "kind");

  AssetUpload upload;
  upload.bytes = file->content;
  upload.size = file->size;
  upload.kind = kind ? kind->content : "";
  upload.fileName = file->fileName;
  upload.contentType = file->contentType;
  const Identity& who = requester(req);
  const AssetOwner owner{who.libraryOwner(), size_t(service.quotaFor(who, &Quotas::uploads)),
                         service.quotaFor(who, &Quotas::uploadBytes)};
  AssetRejection rejection = AssetRejection::None;
  AssetQuotaHit hit;
  Result<AssetRecord> added = service.assets->add(upload, rejection, owner, &hit);
  if (rejection == AssetRejection::QuotaExceeded)
    return sendQuotaExceeded(res, uploadQuotaName(hit.quota), hit.limit, hit.used,
                             added.error().message + " (--quota-" +
                                 (hit.quota == UploadQuota::Uploads ? "uploads " : "upload-bytes ") +
                                 std::to_string(hit.limit) + "); delete one of yours (DELETE /api/assets/{id})");
  if (!added) return sendRejection(res, added.error(), rejection);
  res.set_header("Location", "/api/assets/" + added->id);
  sendJson(res, assetToJson(added.value()), 201);
}

void listAssets(Service& service, const httplib::Request& req, httplib::Response& res) {
  std::optional<AssetKind> kind;
  if (req.has_param("kind")) {
    AssetKind k;
    if (!assetKindFromName(req.get_param_value("kind"), k))
      return sendError(res, ErrorCode::InvalidArgument, "kind must be mesh, texture, environment or measured", "kind");
    kind = k;
  }
  const Identity& who = requester(req);
  nlohmann::json out = nlohmann::json::array();
  for (const AssetRecord& r : service.assets->list(kind))
    if (assetReadable(who, r)) out.push_back(assetToJson(r));
  sendJson(res, out);
}

// Answers from memory only: an id is never turned into a path.
void getAsset(Service& service, const httplib::Request& req, httplib::Response& res) {
  const std::string id = req.matches[1];
  std::optional<AssetRecord> found = service.assets->find(id);
  if (!found || !assetReadable(requester(req), *found))
    return sendError(res, ErrorCode::NotFound, "no asset '" + id.substr(0, 128) + "'", "id");
  sendJson(res, assetToJson(*found));
}

// Removes an upload (its owner, or the teacher); scenes showing it keep it until they change.
void deleteAsset(Service& service, const httplib::Request& req, httplib::Response& res) {
  const std::string id = req.matches[1];
  const Identity& who = requester(req);
  std::optional<AssetRecord> found = service.assets->find(id);
  if (!found || !assetReadable(who, *found))
    return sendError(res, ErrorCode::NotFound, "no asset '" + id.substr(0, 128) + "'", "id");
  if (found->source != AssetSource::Upload)
    return sendError(res, ErrorCode::Conflict, "asset '" + id + "' is built in and cannot be deleted", "id");
  if (!canDelete(who, found->owner))
    return sendError(res, ErrorCode::Forbidden, "only its uploader or the teacher deletes asset '" + id + "'", "id");
  Result<bool> removed = service.assets->remove(id);
  if (!removed) return sendError(res, ErrorCode::StorageError, removed.error().message);
  if (!removed.value()) return sendError(res, ErrorCode::NotFound, "no asset '" + id.substr(0, 128) + "'", "id");
  res.status = 204;
}

}  // namespace

void registerAssetRoutes(httplib::Server& server, Service& service) {
  server.Post("/api/assets", withService(service, uploadAsset));
  server.Get("/api/assets", withService(service, listAssets));
  server.Get("/api/assets/(.+)", withService(service, getAsset));
  server.Delete("/api/assets/(.+)", withService(service, deleteAsset));
}

}  // namespace brdfa::server
