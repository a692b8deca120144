// Uploaded scene assets: meshes (OBJ), textures (PNG, JPEG) and environments (HDR,
// EXR, PNG/JPEG cross cube maps), kept in <dataDir>/assets as `<id>.<ext>` plus `<id>.json`
// (the metadata), and the read-only Blender worlds found in the environment folders.
//
// Nothing a client sends ever becomes a path: ids are generated (kind prefix + 16 random hex
// digits), the original file name is kept for display only, and lookups by id read memory,
// never the file system. Every stored upload is validated by content (brdfa::inspectAsset)
// before it is written, and named to the renderer with Renderer::registerAsset.
#pragma once

#include <cstdint>
#include <map>
#include <set>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "brdfa/assets.h"
#include "brdfa/renderer.h"
#include "brdfa/result.h"
#include "storage/brdf_library.h"

namespace brdfa::server {

class RenderSlots;

struct AssetStoreLimits {
  AssetLimits file;                     // per file: bytes, triangles, pixels
  size_t maxAssets = 1000;              // stored uploads
  uint64_t maxTotalBytes = 4ull << 30;  // all stored upload files together
};

// One file part of a multipart upload, as the client sent it.
struct AssetUpload {
  std::string_view bytes;   // the content; may hold only a prefix when `size` exceeds the limit
  uint64_t size = 0;        // the part's full size in bytes
  std::string kind;         // the `kind` form field; empty: from the content
  std::string fileName;     // the part's file name (display only; checked against the content)
  std::string contentType;  // the part's Content-Type (checked against the content)
};

// Why add() refused an upload, beside the Error (whose code maps to the HTTP status): a stable
// snake_case word for scripts.
enum class AssetRejection {
  None,
  Empty,          // no bytes
  TooLarge,       // over the byte limit (sizes in the message)
  UnknownFormat,  // not OBJ, PNG, JPEG, HDR or EXR by content
  BadKind,        // `kind` is not mesh, texture, environment or measured
  Mislabelled,    // kind, file-name extension or Content-Type contradicts the content
  Invalid,        // inspectAsset refused it: truncated, corrupt, limits exceeded, ...
  StorageFull,    // --max-assets or --max-assets-bytes reached
  Busy,           // no inspection slot within the wait (or shutting down)
  StorageError,   // writing the files failed
  QuotaExceeded,  // the uploader's own count or bytes (AssetOwner) would be exceeded
  MemoryBudget,   // a measured table the renderer's memory budget cannot hold (loaded on upload)
};

// Who uploads, and what they may keep; 0: no limit.
struct AssetOwner {
  std::string user;  // "" for the course (the teacher's uploads, every upload in none mode)
  size_t maxUploads = 0;
  uint64_t maxBytes = 0;
};

// Which per-person limit an upload hit, for the 429.
enum class UploadQuota { Uploads, UploadBytes };
const char* uploadQuotaName(UploadQuota quota);  // "uploads", "upload_bytes": the 429's `quota`
struct AssetQuotaHit {
  UploadQuota quota = UploadQuota::Uploads;
  uint64_t limit = 0, used = 0;
};
const char* assetRejectionName(AssetRejection reason);  // "empty", "too_large", ...

// Where an asset comes from: the renderer's built-ins, Debian blender-data's worlds, an upload.
enum class AssetSource { Builtin, Blender, Upload };
const char* assetSourceName(AssetSource source);  // "builtin", "blender-data", "upload"

// What is known of one asset.
struct AssetRecord {
  std::string id;
  AssetKind kind = AssetKind::Mesh;
  AssetSource source = AssetSource::Upload;
  std::optional<AssetFormat> format;  // unknown for built-ins
  std::string layout;                 // environments: "equirect" | "cross"
  std::string name;                   // uploads: the sanitized original file name
  uint64_t bytes = 0, vertices = 0, triangles = 0;
  int width = 0, height = 0;
  uint64_t measuredBins = 0;  // measured tables: bins with data
  std::string created;        // uploads: ISO 8601 UTC
  std::string owner;          // uploads: the uploader; "" for the course's and others
};

class AssetStore {
 public:
  // `slots` bounds how many uploads are decoded at once (memory); it must outlive the store.
  AssetStore(std::shared_ptr<Renderer> renderer, std::string dataDir, AssetStoreLimits limits, RenderSlots& slots);

  // At start-up: removes leftover temp files, re-registers every stored upload whose metadata
  // and file are intact (others are logged and skipped; a data file without metadata was never
  // acknowledged and is removed), then registers the *.exr files of `environmentDirs` (nullopt:
  // defaultEnvironmentDirs()) as `blender_<stem>`. Returns log lines.
  std::vector<std::string> load(const std::optional<std::vector<std::string>>& environmentDirs);

  // Validates and stores one upload; on success the asset is registered and usable in scenes.
  // On failure `rejection` says why (Error code InvalidArgument/Unsupported -> 400, Internal).
  // `quotaHit` is filled when the rejection is QuotaExceeded.
  Result<AssetRecord> add(const AssetUpload& upload, AssetRejection& rejection, const AssetOwner& owner = {},
                          AssetQuotaHit* quotaHit = nullptr);
  // Forgets an upload and removes its files (metadata first: without it the data file is
  // never loaded again). Scenes already using it keep it until they change; new scenes cannot
  // name it (visible()). false for an unknown id or one that is not an upload.
  Result<bool> remove(const std::string& id);
  // Whether a scene of `user` may name asset `name` (teacher: any): built-ins and Blender
  // worlds yes, an upload when it is the course's or theirs, a removed upload never.
  bool visible(std::string_view name, const std::string& user, bool teacher) const;

  // Every asset: built-ins, Blender worlds, uploads; grouped by kind (mesh, texture,
  // environment), then source in that order, uploads by creation time.
  // Both first pick up uploads stored since by another replica on a shared folder
  // (refreshFromDisk).
  std::vector<AssetRecord> list(std::optional<AssetKind> kind = std::nullopt) const;
  std::optional<AssetRecord> find(const std::string& id) const;
  // A measured upload as the BRDF scenes, analyses and checks name by its id (brdfa/measured.h's
  // measuredBrdf, owned like the upload); null for any other id. Visibility is the caller's
  // (visible()).
  std::shared_ptr<const BrdfEntry> measuredBrdf(std::string_view id) const;
  // The stored data file of upload `id` (its bytes as validated on upload); nullopt for any
  // other id and for removed uploads.
  std::optional<std::string> storedFile(const std::string& id) const;

  // Registers the uploads that other servers sharing the folder stored since the last look
  // (their metadata file is the acknowledgment: written after the data file). Cheap when the
  // folder is unchanged: one stat(). Uploads whose metadata is gone (removed by another
  // server) are forgotten.
  void refreshFromDisk() const;

  // The folder of stored uploads: <dataDir>/assets.
  const std::string& directory() const { return dir_; }

  // Debian blender-data's world folders that exist on this machine.
  static std::vector<std::string> defaultEnvironmentDirs();
  // Ids of uploads: [a-z0-9_]+, at most 64 characters.
  static bool validId(std::string_view id);

 private:
  std::string loadOne(const std::string& id);  // "" on success, else why it was skipped
  void loadEnvironmentDir(const std::string& dir, std::vector<std::string>& log);
  std::string newId(AssetKind kind) const;  // under mutex_
  // Under mutex_: the Error (and rejection) when the owner's quota or the server's caps leave no
  // room for `up`, counting uploads being written.
  std::optional<Error> refuseWithoutRoom(const AssetUpload& up, const AssetOwner& owner, AssetRejection& rejection,
                                         AssetQuotaHit* quotaHit);
  // Writes a reserved upload's files and registers it, then releases the reservation; on failure
  // nothing of it stays.
  Result<void> storeReserved(const AssetRecord& rec, const AssetUpload& up, const AssetOwner& owner);

  std::shared_ptr<Renderer> renderer_;
  std::string dir_;
  AssetStoreLimits limits_;
  RenderSlots& slots_;

  mutable std::mutex mutex_;
  std::map<std::string, AssetRecord> uploads_;                                          // by id
  std::map<std::string, AssetRecord> blender_;                                          // by name
  std::map<std::string, std::shared_ptr<const BrdfEntry>, std::less<>> measuredBrdfs_;  // by measured upload id
  std::set<std::string> writing_;               // ids this server is storing now (not another's to pick up)
  std::set<std::string, std::less<>> removed_;  // uploads removed since start (still registered)
  mutable std::mutex refreshMutex_;             // order: refreshMutex_ before mutex_
  mutable int64_t seenDirStamp_ = -2;           // the folder's mtime (ns) at the last refreshFromDisk
  size_t reserved_ = 0;                         // uploads being written (count toward the cap)
  uint64_t reservedBytes_ = 0;
  uint64_t storedBytes_ = 0;
  // Uploads being written, per uploader: count and bytes (they count toward AssetOwner's limits).
  std::map<std::string, std::pair<size_t, uint64_t>> reservedBy_;
};

// The JSON of an asset as GET /api/assets answers it (also what <id>.json holds, for uploads).
nlohmann::json assetToJson(const AssetRecord& record);

// Display form of a client's file name: the last path component, control characters and
// invalid UTF-8 removed, at most 128 bytes; "" when nothing is left.
std::string sanitizeUploadFileName(std::string_view raw);

}  // namespace brdfa::server
