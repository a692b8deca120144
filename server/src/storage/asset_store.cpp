#include "storage/asset_store.h"

#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>

#include "brdfa/measured.h"
#include "util/atomic_file.h"
#include "util/display_text.h"
#include "util/render_slots.h"

namespace brdfa::server {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr size_t kMaxDisplayName = 128;
constexpr size_t kMaxMetadataBytes = 64 * 1024;
constexpr std::chrono::seconds kInspectSlotWait{30};
// Limits for the environment folders' files (the system's, not a client's).
constexpr uint64_t kMaxSystemAssetBytes = 1ull << 30;
constexpr AssetKind kKinds[] = {AssetKind::Mesh, AssetKind::Texture, AssetKind::Environment, AssetKind::Measured};

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out)
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  return out;
}

// Per format: the extension a stored file gets (and file names are checked against), and the
// name messages use. In AssetFormat's order.
struct FormatInfo {
  AssetFormat format;
  const char* extension;
  const char* title;
};
constexpr FormatInfo kFormatInfo[] = {
    {AssetFormat::Obj, "obj", "OBJ"},     {AssetFormat::Png, "png", "PNG"},
    {AssetFormat::Jpeg, "jpg", "JPEG"},   {AssetFormat::Hdr, "hdr", "Radiance HDR"},
    {AssetFormat::Exr, "exr", "OpenEXR"}, {AssetFormat::Merl, "binary", "a MERL table"},
};
const char* storedExtension(AssetFormat format) { return kFormatInfo[static_cast<int>(format)].extension; }
const char* formatTitle(AssetFormat format) { return kFormatInfo[static_cast<int>(format)].title; }

std::optional<AssetFormat> formatFromName(std::string_view name) {
  for (const FormatInfo& f : kFormatInfo)
    if (name == assetFormatName(f.format)) return f.format;
  return std::nullopt;
}

// A file-name extension this service knows: .obj .png .jpg .jpeg .hdr .exr.
std::optional<AssetFormat> formatFromExtension(std::string_view fileName) {
  size_t dot = fileName.rfind('.');
  if (dot == std::string_view::npos) return std::nullopt;
  std::string ext = lower(fileName.substr(dot + 1));
  if (ext == "jpeg") return AssetFormat::Jpeg;
  for (const FormatInfo& f : kFormatInfo)
    if (ext == f.extension) return f.format;
  return std::nullopt;
}

// What a part's Content-Type claims: nothing (absent or generic), a known format, or some
// other image/model/audio/video type (which contradicts every content we accept).
struct TypeClaim {
  bool claims = false;
  std::optional<AssetFormat> format;
};

TypeClaim claimOfContentType(std::string_view contentType) {
  std::string t = lower(contentType.substr(0, contentType.find(';')));
  t.erase(0, t.find_first_not_of(" \t"));
  t.erase(t.find_last_not_of(" \t") + 1);
  struct Known {
    const char* type;
    AssetFormat format;
  };
  static const Known known[] = {
      {"image/png", AssetFormat::Png},
      {"image/x-png", AssetFormat::Png},
      {"image/jpeg", AssetFormat::Jpeg},
      {"image/jpg", AssetFormat::Jpeg},
      {"image/pjpeg", AssetFormat::Jpeg},
      {"image/vnd.radiance", AssetFormat::Hdr},
      {"image/x-hdr", AssetFormat::Hdr},
      {"image/x-radiance", AssetFormat::Hdr},
      {"image/aces", AssetFormat::Exr},
      {"image/x-exr", AssetFormat::Exr},
      {"application/x-exr", AssetFormat::Exr},
      {"model/obj", AssetFormat::Obj},
      {"text/x-obj", AssetFormat::Obj},
      {"model/x-obj", AssetFormat::Obj},
      // /etc/mime.types maps .obj to tgif's type, so browsers on Linux may send it for OBJ.
      {"application/x-tgif", AssetFormat::Obj},
      {"application/x-wavefront-obj", AssetFormat::Obj},
  };
  for (const Known& k : known)
    if (t == k.type) return {true, k.format};
  for (const char* prefix : {"image/", "model/", "audio/", "video/"})
    if (t.starts_with(prefix)) return {true, std::nullopt};
  return {};
}

bool kindAccepts(AssetKind kind, AssetFormat format) {
  switch (kind) {
    case AssetKind::Mesh: return format == AssetFormat::Obj;
    case AssetKind::Texture: return format == AssetFormat::Png || format == AssetFormat::Jpeg;
    case AssetKind::Environment:  // HDR, EXR, or a PNG/JPEG cross
      return format != AssetFormat::Obj && format != AssetFormat::Merl;
    case AssetKind::Measured: return format == AssetFormat::Merl;
  }
  return false;
}

// Without a `kind` field: OBJ -> mesh, HDR/EXR -> environment, PNG/JPEG -> texture, MERL ->
// measured.
AssetKind defaultKind(AssetFormat format) {
  switch (format) {
    case AssetFormat::Obj: return AssetKind::Mesh;
    case AssetFormat::Merl: return AssetKind::Measured;
    case AssetFormat::Hdr:
    case AssetFormat::Exr: return AssetKind::Environment;
    default: return AssetKind::Texture;
  }
}

const char* idPrefix(AssetKind kind) {
  switch (kind) {
    case AssetKind::Texture: return "tex_";
    case AssetKind::Environment: return "env_";
    case AssetKind::Measured: return "merl_";
    case AssetKind::Mesh: break;
  }
  return "mesh_";
}

// An environment name from a Blender world's file stem: lower case, [a-z0-9_] only.
std::string blenderName(const std::string& stem) {
  std::string out = "blender_";
  for (char c : lower(stem)) out += (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') ? c : '_';
  return out.size() > 8 && AssetStore::validId(out) ? out : std::string();
}

// The file's bytes when it is a regular file of at most `maxBytes` (a link to one only when
// `followLinks`: the store's own folder holds no links).
std::optional<std::string> readSmallFile(const fs::path& path, size_t maxBytes, bool followLinks = false) {
  std::error_code ec;
  const fs::file_status st = followLinks ? fs::status(path, ec) : fs::symlink_status(path, ec);
  if (!fs::is_regular_file(st) || fs::file_size(path, ec) > maxBytes || ec) return std::nullopt;
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// A stored upload's metadata, checked field by field; `why` says what is wrong.
std::optional<AssetRecord> recordFromMetadata(const json& j, const std::string& id, std::string& why) {
  auto str = [&](const char* key) -> std::optional<std::string> {
    auto it = j.find(key);
    if (it == j.end() || !it->is_string()) return std::nullopt;
    return it->get<std::string>();
  };
  auto count = [&](const char* key, uint64_t& dst) {
    auto it = j.find(key);
    if (it == j.end() || !it->is_number_unsigned()) return false;
    dst = it->get<uint64_t>();
    return true;
  };
  if (!j.is_object()) return why = "metadata is not a JSON object", std::nullopt;
  AssetRecord r;
  r.id = id;
  r.source = AssetSource::Upload;
  auto storedId = str("id");
  auto kind = str("kind");
  auto format = str("format");
  if (!storedId || *storedId != id) return why = "metadata id does not match its file name", std::nullopt;
  if (!kind || !assetKindFromName(*kind, r.kind)) return why = "metadata has no valid kind", std::nullopt;
  if (!format || !(r.format = formatFromName(*format)) || !kindAccepts(r.kind, *r.format))
    return why = "metadata has no valid format for its kind", std::nullopt;
  uint64_t width = 0, height = 0;
  if (!count("bytes", r.bytes) || !count("vertices", r.vertices) || !count("triangles", r.triangles) ||
      !count("width", width) || !count("height", height) || width > (1u << 30) || height > (1u << 30))
    return why = "metadata lacks bytes, vertices, triangles, width or height", std::nullopt;
  r.width = static_cast<int>(width);
  r.height = static_cast<int>(height);
  r.layout = str("layout").value_or("");
  r.name = sanitizeUploadFileName(str("name").value_or(""));
  r.created = str("created").value_or("");
  r.owner = str("owner").value_or("");  // absent in uploads of the single-user layout: the course's
  if (r.kind == AssetKind::Measured) (void)count("bins", r.measuredBins);
  return r;
}

// The BRDF a measured upload is: brdfa/measured.h's file bound to its table, the uploader's.
std::shared_ptr<const BrdfEntry> measuredEntry(const AssetRecord& r) {
  auto entry = std::make_shared<BrdfEntry>();
  entry->name = r.id;
  entry->source = measuredBrdfText();
  Result<BrdfDefinition> def = measuredBrdf(r.id);
  // The text is the renderer's own: it always parses (tests/unit/test_measured_render.cpp).
  if (def) entry->definition = std::make_shared<const BrdfDefinition>(std::move(def.value()));
  entry->owner = r.owner;
  return entry->definition ? entry : nullptr;
}

}  // namespace

const char* assetSourceName(AssetSource source) {
  switch (source) {
    case AssetSource::Builtin: return "builtin";
    case AssetSource::Blender: return "blender-data";
    case AssetSource::Upload: return "upload";
  }
  return "upload";
}

const char* uploadQuotaName(UploadQuota quota) { return quota == UploadQuota::Uploads ? "uploads" : "upload_bytes"; }

const char* assetRejectionName(AssetRejection reason) {
  switch (reason) {
    case AssetRejection::None: return "none";
    case AssetRejection::Empty: return "empty";
    case AssetRejection::TooLarge: return "too_large";
    case AssetRejection::UnknownFormat: return "unknown_format";
    case AssetRejection::BadKind: return "bad_kind";
    case AssetRejection::Mislabelled: return "mislabelled";
    case AssetRejection::Invalid: return "invalid";
    case AssetRejection::StorageFull: return "storage_full";
    case AssetRejection::Busy: return "busy";
    case AssetRejection::StorageError: return "storage_error";
    case AssetRejection::QuotaExceeded: return "quota_exceeded";
    case AssetRejection::MemoryBudget: return "memory_budget";
  }
  return "invalid";
}

json assetToJson(const AssetRecord& r) {
  json j{{"id", r.id},
         {"kind", assetKindName(r.kind)},
         {"builtin", r.source != AssetSource::Upload},
         {"source", assetSourceName(r.source)}};
  if (r.source == AssetSource::Builtin) {
    j["name"] = r.id;
    return j;
  }
  j["name"] = r.source == AssetSource::Upload ? r.name : r.id;
  j["format"] = r.format ? json(assetFormatName(*r.format)) : json(nullptr);
  j["layout"] = r.layout.empty() ? json(nullptr) : json(r.layout);
  j["bytes"] = r.bytes;
  j["width"] = r.width;
  j["height"] = r.height;
  if (r.kind == AssetKind::Measured) j["bins"] = r.measuredBins;
  if (r.source == AssetSource::Upload) {
    j["vertices"] = r.vertices;
    j["triangles"] = r.triangles;
    j["created"] = r.created;
    j["owner"] = r.owner.empty() ? json(nullptr) : json(r.owner);
  }
  return j;
}

namespace {

// The code point of the valid n-byte UTF-8 sequence at raw[i].
}  // namespace

std::string sanitizeUploadFileName(std::string_view raw) {
  // Only the last path component, whichever separator the client's system uses.
  if (size_t slash = raw.find_last_of("/\\"); slash != std::string_view::npos) raw.remove_prefix(slash + 1);
  std::string out = cleanDisplayText(raw, kMaxDisplayName);
  if (out == "." || out == "..") out.clear();
  return out;
}

bool AssetStore::validId(std::string_view id) {
  if (id.empty() || id.size() > 64) return false;
  return std::all_of(id.begin(), id.end(),
                     [](char c) { return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_'; });
}

std::vector<std::string> AssetStore::defaultEnvironmentDirs() {
  const fs::path base = "/usr/share/blender";
  const fs::path world = fs::path("datafiles") / "studiolights" / "world";
  std::vector<fs::path> candidates = {base / world};
  std::error_code ec;
  std::vector<fs::path> versions;  // /usr/share/blender/<version>/datafiles/...
  for (fs::directory_iterator it(base, ec), end; !ec && it != end; it.increment(ec))
    if (it->is_directory(ec)) versions.push_back(it->path());
  std::sort(versions.begin(), versions.end());
  for (const fs::path& v : versions) candidates.push_back(v / world);

  std::vector<std::string> out;
  std::set<fs::path> seen;
  for (const fs::path& dir : candidates) {
    if (!fs::is_directory(dir, ec)) continue;
    fs::path canonical = fs::canonical(dir, ec);
    if (ec || !seen.insert(canonical).second) continue;
    out.push_back(dir.string());
  }
  return out;
}

AssetStore::AssetStore(std::shared_ptr<Renderer> renderer, std::string dataDir, AssetStoreLimits limits,
                       RenderSlots& slots)
    : renderer_(std::move(renderer)),
      dir_((fs::absolute(fs::path(dataDir)) / "assets").lexically_normal().string()),
      limits_(limits),
      slots_(slots) {}

std::string AssetStore::loadOne(const std::string& id) {
  const fs::path meta = fs::path(dir_) / (id + ".json");
  std::optional<std::string> text = readSmallFile(meta, kMaxMetadataBytes);
  if (!text) return "metadata unreadable or larger than " + std::to_string(kMaxMetadataBytes) + " bytes";
  json j = json::parse(*text, nullptr, /*allow_exceptions=*/false);
  std::string why;
  std::optional<AssetRecord> record = recordFromMetadata(j, id, why);
  if (!record) return why;
  const fs::path data = fs::path(dir_) / (id + "." + storedExtension(*record->format));
  std::error_code ec;
  if (!fs::is_regular_file(fs::symlink_status(data, ec))) return "its file " + data.filename().string() + " is missing";
  if (fs::file_size(data, ec) != record->bytes || ec)
    return "its file " + data.filename().string() + " does not have the recorded size";
  if (Result<void> r = renderer_->registerAsset(id, record->kind, data.string()); !r) return r.error().message;
  std::lock_guard lock(mutex_);
  if (uploads_.count(id)) return "";  // picked up twice: counted once
  storedBytes_ += record->bytes;
  if (record->kind == AssetKind::Measured) measuredBrdfs_[id] = measuredEntry(*record);
  uploads_[id] = std::move(*record);
  return "";
}

void AssetStore::loadEnvironmentDir(const std::string& dir, std::vector<std::string>& log) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    log.push_back("warning: environment folder " + dir + " does not exist; skipped");
    return;
  }
  std::vector<fs::path> files;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
    if (lower(it->path().extension().string()) == ".exr" && it->is_regular_file(ec)) files.push_back(it->path());
  std::sort(files.begin(), files.end());
  for (const fs::path& file : files) {
    const std::string name = blenderName(file.stem().string());
    bool taken = false;
    {
      std::lock_guard lock(mutex_);
      taken = blender_.count(name) > 0;
    }
    if (name.empty() || taken) {
      log.push_back("warning: environment " + file.string() + " skipped (" +
                    (name.empty() ? "no usable name" : "'" + name + "' already registered") + ")");
      continue;
    }
    // Only sniffed here, decoded when a scene first uses it: a full decode and cube conversion
    // of every world would be slow, and start-up must not grow with what is installed. A world that
    // turns out unreadable then fails that scene with the decoder's reason, naming the world.
    std::optional<std::string> bytes = readSmallFile(file, kMaxSystemAssetBytes, /*followLinks=*/true);
    std::optional<AssetFormat> format = bytes ? sniffAssetFormat(*bytes) : std::nullopt;
    Result<void> registered =
        format == AssetFormat::Exr
            ? renderer_->registerAsset(name, AssetKind::Environment, fs::absolute(file, ec).string())
            : Result<void>(
                  makeError(ErrorCode::InvalidArgument,
                            bytes ? "not an EXR file"
                                  : "unreadable, or larger than " + std::to_string(kMaxSystemAssetBytes) + " bytes"));
    if (!registered) {
      log.push_back("warning: environment " + file.string() + " (" + name + ") skipped: " + registered.error().message);
      continue;
    }
    AssetRecord rec;
    rec.id = name;
    rec.kind = AssetKind::Environment;
    rec.source = AssetSource::Blender;
    rec.format = AssetFormat::Exr;
    rec.layout = "equirect";
    rec.bytes = bytes->size();
    std::lock_guard lock(mutex_);
    blender_[name] = std::move(rec);
  }
}

std::vector<std::string> AssetStore::load(const std::optional<std::vector<std::string>>& environmentDirs) {
  std::vector<std::string> log;
  std::error_code ec;
  fs::create_directories(dir_, ec);
  if (ec) log.push_back("warning: cannot create asset folder " + dir_ + ": " + ec.message());
  removeStaleTempFiles(dir_);

  // Stems of metadata files, and data files by stem.
  std::set<std::string> metaIds;
  std::vector<fs::path> dataFiles;
  for (fs::directory_iterator it(dir_, ec), end; !ec && it != end; it.increment(ec)) {
    const fs::path& p = it->path();
    const std::string stem = p.stem().string();
    if (!validId(stem)) continue;  // not a name this store writes (temp files start with '.')
    if (p.extension() == ".json")
      metaIds.insert(stem);
    else
      dataFiles.push_back(p);
  }
  for (const std::string& id : metaIds)
    if (std::string why = loadOne(id); !why.empty()) log.push_back("warning: upload " + id + " skipped: " + why);
  // A data file without metadata: the write was interrupted before the upload was acknowledged.
  for (const fs::path& p : dataFiles) {
    if (metaIds.count(p.stem().string()) || !formatFromExtension(p.filename().string())) continue;
    // Replicas share the folder: a young one may be another server's upload in progress.
    std::error_code tec;
    const auto written = fs::last_write_time(p, tec);
    if (tec || fs::file_time_type::clock::now() - written < kTempFileAbandonedAfter) continue;
    log.push_back("warning: removing " + p.filename().string() + ": an interrupted upload (no metadata)");
    (void)removeFileDurably(p);
  }

  for (const std::string& dir : environmentDirs ? *environmentDirs : defaultEnvironmentDirs())
    loadEnvironmentDir(dir, log);
  return log;
}

std::string AssetStore::newId(AssetKind kind) const {
  std::random_device device;
  for (;;) {
    const uint64_t bits = (static_cast<uint64_t>(device()) << 32) ^ device();
    char hex[17];
    std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(bits));
    std::string id = std::string(idPrefix(kind)) + hex;
    std::error_code ec;
    if (!uploads_.count(id) && !fs::exists(fs::path(dir_) / (id + ".json"), ec)) return id;
  }
}

namespace {

// An upload refused before anything was stored: `why` into `rejection`, the Error returned.
Error refuseUpload(AssetRejection& rejection, AssetRejection why, std::string message, std::string field = "file") {
  rejection = why;
  return makeError(ErrorCode::InvalidArgument, std::move(message), std::move(field));
}

// What an upload's content is, once it agrees with everything the request says about it.
struct UploadClaims {
  AssetKind kind;
  AssetFormat format;
  std::string displayName;
};

// The cheap checks: size, then what the content is against what the request says it is.
Result<UploadClaims> checkUploadClaims(const AssetUpload& up, uint64_t maxBytes, AssetRejection& rejection) {
  if (up.size == 0) return refuseUpload(rejection, AssetRejection::Empty, "the uploaded file is empty");
  if (up.size > maxBytes)
    return refuseUpload(rejection, AssetRejection::TooLarge,
                        "the file is " + std::to_string(up.size) + " bytes; uploads are limited to " +
                            std::to_string(maxBytes) + " bytes (--max-upload-bytes)");
  std::optional<AssetKind> requested;
  if (!up.kind.empty()) {
    AssetKind k;
    if (!assetKindFromName(up.kind, k))
      return refuseUpload(rejection, AssetRejection::BadKind,
                          "kind must be mesh, texture, environment or measured, got '" + up.kind.substr(0, 64) + "'",
                          "kind");
    requested = k;
  }
  std::optional<AssetFormat> format = sniffAssetFormat(up.bytes);
  if (!format)
    return refuseUpload(rejection, AssetRejection::UnknownFormat,
                        "the file's content is none of OBJ, PNG, JPEG, Radiance HDR, OpenEXR or a MERL table");
  const AssetKind kind = requested.value_or(defaultKind(*format));
  if (!kindAccepts(kind, *format))
    return refuseUpload(rejection, AssetRejection::Mislabelled,
                        std::string("kind '") + assetKindName(kind) + "' cannot be " + formatTitle(*format) +
                            " content (mesh: OBJ; texture: PNG or JPEG; environment: HDR, EXR, or a PNG/JPEG cross)",
                        "kind");
  std::string displayName = sanitizeUploadFileName(up.fileName);
  if (auto named = formatFromExtension(displayName); named && *named != *format)
    return refuseUpload(rejection, AssetRejection::Mislabelled,
                        "the file name '" + displayName + "' says " + formatTitle(*named) + " but the content is " +
                            formatTitle(*format));
  if (TypeClaim claim = claimOfContentType(up.contentType); claim.claims && claim.format != format)
    return refuseUpload(rejection, AssetRejection::Mislabelled,
                        "the part's Content-Type '" + up.contentType.substr(0, 128) + "' contradicts its content (" +
                            formatTitle(*format) + ")");
  return UploadClaims{kind, *format, std::move(displayName)};
}

}  // namespace

std::optional<Error> AssetStore::refuseWithoutRoom(const AssetUpload& up, const AssetOwner& owner,
                                                   AssetRejection& rejection, AssetQuotaHit* quotaHit) {
  if (owner.maxUploads > 0 || owner.maxBytes > 0) {
    size_t count = reservedBy_[owner.user].first;
    uint64_t bytes = reservedBy_[owner.user].second;
    for (const auto& [id, r] : uploads_)
      if (r.owner == owner.user) ++count, bytes += r.bytes;
    AssetQuotaHit hit;
    bool over = true;
    if (owner.maxUploads > 0 && count >= owner.maxUploads)
      hit = {UploadQuota::Uploads, owner.maxUploads, count};
    else if (owner.maxBytes > 0 && bytes + up.size > owner.maxBytes)
      hit = {UploadQuota::UploadBytes, owner.maxBytes, bytes};
    else
      over = false;
    if (over) {
      if (quotaHit) *quotaHit = hit;
      return refuseUpload(rejection, AssetRejection::QuotaExceeded,
                          hit.quota == UploadQuota::Uploads
                              ? "you keep " + std::to_string(count) + " uploads, the most one person may"
                              : "your uploads hold " + std::to_string(bytes) + " bytes; with this file's " +
                                    std::to_string(up.size) + " they would pass your " +
                                    std::to_string(owner.maxBytes) + "-byte quota");
    }
  }
  if (uploads_.size() + reserved_ >= limits_.maxAssets)
    return refuseUpload(
        rejection, AssetRejection::StorageFull,
        "the server keeps at most " + std::to_string(limits_.maxAssets) + " uploads (--max-assets); none can be added");
  const uint64_t used = storedBytes_ + reservedBytes_;
  if (used + up.size > limits_.maxTotalBytes)
    return refuseUpload(rejection, AssetRejection::StorageFull,
                        "stored uploads would exceed " + std::to_string(limits_.maxTotalBytes) +
                            " bytes (--max-assets-bytes); " +
                            std::to_string(limits_.maxTotalBytes - std::min(limits_.maxTotalBytes, used)) +
                            " bytes are left, the file has " + std::to_string(up.size));
  return std::nullopt;
}

Result<void> AssetStore::storeReserved(const AssetRecord& rec, const AssetUpload& up, const AssetOwner& owner) {
  // The data file first, then the metadata: a metadata file always names a complete file.
  const fs::path data = fs::path(dir_) / (rec.id + "." + storedExtension(*rec.format));
  const fs::path meta = fs::path(dir_) / (rec.id + ".json");
  Result<void> written = writeFileAtomically(data, up.bytes);
  if (written)
    written = writeFileAtomically(meta, assetToJson(rec).dump(2, ' ', false, json::error_handler_t::replace) + "\n");
  if (written) written = renderer_->registerAsset(rec.id, rec.kind, data.string());

  std::lock_guard lock(mutex_);
  writing_.erase(rec.id);
  --reserved_;
  reservedBytes_ -= up.size;
  if (auto it = reservedBy_.find(owner.user); it != reservedBy_.end() && --it->second.first == 0)
    reservedBy_.erase(it);
  else if (it != reservedBy_.end())
    it->second.second -= up.size;
  if (!written) {
    (void)removeFileDurably(meta);
    (void)removeFileDurably(data);
    return written;
  }
  storedBytes_ += rec.bytes;
  uploads_[rec.id] = rec;
  if (rec.kind == AssetKind::Measured) measuredBrdfs_[rec.id] = measuredEntry(rec);
  return {};
}

Result<AssetRecord> AssetStore::add(const AssetUpload& up, AssetRejection& rejection, const AssetOwner& owner,
                                    AssetQuotaHit* quotaHit) {
  rejection = AssetRejection::None;
  BRDFA_TRY_ASSIGN(UploadClaims claims, checkUploadClaims(up, limits_.file.maxBytes, rejection));
  const AssetKind kind = claims.kind;

  // Under mutex_: the uploader's quota, then the server's caps, counting uploads being written
  // (the uploader's own in-flight ones count as kept: `reservedBy_`). Other replicas' uploads
  // count against the same quotas and caps: the folder is shared.
  refreshFromDisk();
  {
    std::lock_guard lock(mutex_);
    if (auto full = refuseWithoutRoom(up, owner, rejection, quotaHit)) return *full;
  }

  // Decoding a large image takes memory and time: a few at once.
  if (!slots_.acquire(kInspectSlotWait)) {
    rejection = AssetRejection::Busy;
    return makeError(ErrorCode::Internal, "too many uploads are being checked; retry later");
  }
  Result<AssetInfo> info = inspectAsset(up.bytes, kind, limits_.file);
  slots_.release();
  if (!info) {
    rejection = AssetRejection::Invalid;
    Error e = info.takeError();
    if (e.field.empty()) e.field = "file";
    return e;
  }

  AssetRecord rec;
  rec.kind = kind;
  rec.source = AssetSource::Upload;
  rec.format = info->format;
  rec.layout = info->layout;
  rec.name = claims.displayName;
  rec.bytes = up.size;
  rec.vertices = info->vertices;
  rec.triangles = info->triangles;
  rec.width = info->width;
  rec.height = info->height;
  rec.measuredBins = info->measuredBins;
  rec.created = nowIso8601();
  rec.owner = owner.user;
  refreshFromDisk();  // the check took a while: look at the folder again before reserving
  {
    std::lock_guard lock(mutex_);
    if (auto full = refuseWithoutRoom(up, owner, rejection, quotaHit)) return *full;
    rec.id = newId(kind);
    writing_.insert(rec.id);
    ++reserved_;
    reservedBytes_ += up.size;
    ++reservedBy_[owner.user].first;
    reservedBy_[owner.user].second += up.size;
  }
  if (Result<void> stored = storeReserved(rec, up, owner); !stored) {
    // A measured table is loaded when it is registered: a budget that cannot hold it refuses it.
    if (stored.error().code == ErrorCode::OverBudget) {
      rejection = AssetRejection::MemoryBudget;
      return stored.takeError();
    }
    rejection = AssetRejection::StorageError;
    return makeError(ErrorCode::Internal, "could not store the upload: " + stored.error().message);
  }
  return rec;
}

void AssetStore::refreshFromDisk() const {
  std::lock_guard refresh(refreshMutex_);
  struct stat st {};
  if (::stat(dir_.c_str(), &st) != 0) return;
  const int64_t stamp = int64_t(st.st_mtim.tv_sec) * 1'000'000'000 + st.st_mtim.tv_nsec;
  const int64_t now =
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
  // A new metadata file (a rename into the folder) changes its mtime; a change in the same clock
  // tick as the last look would not, so a stamp under a second old is never trusted.
  if (stamp == seenDirStamp_ && now - stamp > 1'000'000'000) return;
  seenDirStamp_ = stamp;
  std::vector<std::string> fresh;
  {
    std::lock_guard lock(mutex_);
    std::error_code ec;
    std::set<std::string> present;
    for (fs::directory_iterator it(dir_, ec), end; !ec && it != end; it.increment(ec)) {
      const fs::path& p = it->path();
      const std::string stem = p.stem().string();
      if (p.extension() != ".json" || !validId(stem)) continue;
      present.insert(stem);
      if (!uploads_.count(stem) && !writing_.count(stem) && !removed_.count(stem)) fresh.push_back(stem);
    }
    // Another server removed these (a listing that failed part-way removes nothing). Like
    // loadOne, this changes what the store holds from a const lookup.
    AssetStore& self = const_cast<AssetStore&>(*this);
    for (auto it = self.uploads_.begin(); !ec && it != self.uploads_.end();) {
      if (present.count(it->first) || writing_.count(it->first)) {
        ++it;
        continue;
      }
      self.storedBytes_ -= it->second.bytes;
      self.removed_.insert(it->first);
      it = self.uploads_.erase(it);
    }
  }
  for (const std::string& id : fresh)
    if (std::string why = const_cast<AssetStore*>(this)->loadOne(id); !why.empty())
      std::fprintf(stderr, "warning: upload %s stored by another server skipped: %s\n", id.c_str(), why.c_str());
}

std::vector<AssetRecord> AssetStore::list(std::optional<AssetKind> kind) const {
  refreshFromDisk();
  std::vector<AssetRecord> out;
  std::lock_guard lock(mutex_);
  for (AssetKind k : kKinds) {
    if (kind && *kind != k) continue;
    // Measured tables have no built-ins: every one is an upload.
    const std::vector<std::string> names = k == AssetKind::Mesh          ? renderer_->meshNames()
                                           : k == AssetKind::Texture     ? renderer_->textureNames()
                                           : k == AssetKind::Environment ? renderer_->environmentNames()
                                                                         : std::vector<std::string>{};
    // Built-ins: what the renderer knows that this store did not register.
    for (const std::string& n : names) {
      if (uploads_.count(n) || blender_.count(n)) continue;
      AssetRecord r;
      r.id = n;
      r.kind = k;
      r.source = AssetSource::Builtin;
      out.push_back(std::move(r));
    }
    for (const auto& [name, r] : blender_)
      if (r.kind == k) out.push_back(r);
    const size_t firstUpload = out.size();
    for (const auto& [id, r] : uploads_)
      if (r.kind == k) out.push_back(r);
    std::stable_sort(out.begin() + static_cast<std::ptrdiff_t>(firstUpload), out.end(),
                     [](const AssetRecord& a, const AssetRecord& b) { return a.created < b.created; });
  }
  return out;
}

Result<bool> AssetStore::remove(const std::string& id) {
  AssetRecord record;
  {
    std::lock_guard lock(mutex_);
    auto it = uploads_.find(id);
    if (it == uploads_.end()) return false;
    record = std::move(it->second);
    measuredBrdfs_.erase(id);
    uploads_.erase(it);
    storedBytes_ -= record.bytes;
    removed_.insert(id);
  }
  Result<void> gone = removeFileDurably(fs::path(dir_) / (id + ".json"));
  if (gone) gone = removeFileDurably(fs::path(dir_) / (id + "." + storedExtension(*record.format)));
  if (!gone && gone.error().code != ErrorCode::NotFound) return gone.takeError();
  return true;
}

bool AssetStore::visible(std::string_view name, const std::string& user, bool teacher) const {
  std::lock_guard lock(mutex_);
  if (removed_.count(name)) return false;
  auto it = uploads_.find(std::string(name));
  return it == uploads_.end() || teacher || it->second.owner.empty() || it->second.owner == user;
}

std::optional<AssetRecord> AssetStore::find(const std::string& id) const {
  refreshFromDisk();
  {
    std::lock_guard lock(mutex_);
    if (auto it = uploads_.find(id); it != uploads_.end()) return it->second;
    if (auto it = blender_.find(id); it != blender_.end()) return it->second;
  }
  for (const AssetRecord& r : list())
    if (r.id == id) return r;
  return std::nullopt;
}

std::optional<std::string> AssetStore::storedFile(const std::string& id) const {
  std::lock_guard lock(mutex_);
  auto it = uploads_.find(id);
  if (it == uploads_.end() || removed_.count(id) || !it->second.format) return std::nullopt;
  return (fs::path(dir_) / (id + "." + storedExtension(*it->second.format))).string();
}

std::shared_ptr<const BrdfEntry> AssetStore::measuredBrdf(std::string_view id) const {
  if (!id.starts_with("merl_")) return nullptr;  // every other name: no folder look-up
  refreshFromDisk();
  std::lock_guard lock(mutex_);
  auto it = measuredBrdfs_.find(id);
  return it == measuredBrdfs_.end() ? nullptr : it->second;
}

}  // namespace brdfa::server
