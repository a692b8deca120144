#include "brdfa/assets.h"

#include "brdfa/measured.h"

#include "assets/image_decode.h"
#include "assets/obj_loader.h"

namespace brdfa {

const char* assetKindName(AssetKind kind) {
  switch (kind) {
    case AssetKind::Texture: return "texture";
    case AssetKind::Environment: return "environment";
    case AssetKind::Measured: return "measured";
    default: return "mesh";
  }
}

bool assetKindFromName(std::string_view name, AssetKind& kind) {
  for (AssetKind k : {AssetKind::Mesh, AssetKind::Texture, AssetKind::Environment, AssetKind::Measured})
    if (name == assetKindName(k)) {
      kind = k;
      return true;
    }
  return false;
}

const char* assetFormatName(AssetFormat format) {
  switch (format) {
    case AssetFormat::Png: return "png";
    case AssetFormat::Jpeg: return "jpeg";
    case AssetFormat::Hdr: return "hdr";
    case AssetFormat::Exr: return "exr";
    case AssetFormat::Merl: return "merl";
    default: return "obj";
  }
}

namespace {

bool startsWith(std::string_view bytes, std::string_view prefix) { return bytes.substr(0, prefix.size()) == prefix; }

bool isBlank(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

// True when `line` (leading blanks removed) starts with an OBJ statement keyword followed by
// whitespace. Only statements that open real files: v, vn, vt, f, o, g, s, l, p, mtllib, usemtl.
bool isObjStatement(std::string_view line) {
  static const std::string_view kKeywords[] = {"v", "vn", "vt", "f", "o", "g", "s", "l", "p", "mtllib", "usemtl"};
  for (std::string_view keyword : kKeywords)
    if (line.size() > keyword.size() && startsWith(line, keyword) && isBlank(line[keyword.size()])) return true;
  return false;
}

// OBJ is text: no NUL byte in the first 4 KiB, and the first line that is neither blank nor a
// comment is an OBJ statement. Only the first 64 KiB are read, enough for any comment header.
bool looksLikeObj(std::string_view bytes) {
  if (bytes.substr(0, 4096).find('\0') != std::string_view::npos) return false;
  std::string_view text = bytes.substr(0, 64 * 1024);
  while (!text.empty()) {
    size_t end = text.find('\n');
    std::string_view line = text.substr(0, end);
    text = end == std::string_view::npos ? std::string_view() : text.substr(end + 1);
    size_t first = 0;
    while (first < line.size() && isBlank(line[first])) ++first;
    line.remove_prefix(first);
    if (line.empty() || line[0] == '#') continue;
    return isObjStatement(line);
  }
  return false;
}

}  // namespace

std::optional<AssetFormat> sniffAssetFormat(std::string_view bytes) {
  // Magic numbers: PNG spec 5.2, JPEG SOI + the first marker's 0xFF, Radiance's program
  // identifier line, OpenEXR's 4-byte magic 20000630 little-endian.
  if (startsWith(bytes, std::string_view("\x89PNG\r\n\x1a\n", 8))) return AssetFormat::Png;
  if (startsWith(bytes, "\xFF\xD8\xFF")) return AssetFormat::Jpeg;
  if (startsWith(bytes, "#?RADIANCE") || startsWith(bytes, "#?RGBE")) return AssetFormat::Hdr;
  if (startsWith(bytes, std::string_view("\x76\x2F\x31\x01", 4))) return AssetFormat::Exr;
  if (hasMerlHeader(bytes)) return AssetFormat::Merl;  // int32 90, 90, 180: never text, never an image
  if (looksLikeObj(bytes)) return AssetFormat::Obj;
  return std::nullopt;
}

namespace {

// How a format is named to a user: "a PNG image".
const char* formatDescription(AssetFormat format) {
  switch (format) {
    case AssetFormat::Png: return "a PNG image";
    case AssetFormat::Jpeg: return "a JPEG image";
    case AssetFormat::Hdr: return "a Radiance HDR image";
    case AssetFormat::Exr: return "an OpenEXR image";
    case AssetFormat::Merl: return "a MERL measured BRDF table";
    default: return "an OBJ mesh";
  }
}

// What a kind accepts, named to a user: "a mesh (OBJ)".
const char* kindDescription(AssetKind kind) {
  switch (kind) {
    case AssetKind::Texture: return "a texture (PNG or JPEG)";
    case AssetKind::Environment: return "an environment (equirectangular HDR or EXR, or a PNG or JPEG cross cube map)";
    case AssetKind::Measured: return "a measured BRDF (a MERL .binary table)";
    default: return "a mesh (OBJ)";
  }
}

bool kindAccepts(AssetKind kind, AssetFormat format) {
  switch (kind) {
    case AssetKind::Mesh: return format == AssetFormat::Obj;
    case AssetKind::Texture: return format == AssetFormat::Png || format == AssetFormat::Jpeg;
    case AssetKind::Measured: return format == AssetFormat::Merl;
    default: return format != AssetFormat::Obj && format != AssetFormat::Merl;
  }
}

Result<AssetInfo> inspectMesh(std::string_view bytes, const AssetLimits& limits) {
  AssetInfo info;
  auto mesh = loadObjMesh(bytes, limits, &info);
  if (!mesh) return mesh.takeError();
  info.kind = AssetKind::Mesh;
  info.format = AssetFormat::Obj;
  return info;
}

Result<AssetInfo> inspectTexture(std::string_view bytes, AssetFormat format, const AssetLimits& limits) {
  auto texture = decodeTexture(bytes, limits);
  if (!texture) return texture.takeError();
  AssetInfo info;
  info.kind = AssetKind::Texture;
  info.format = format;
  info.width = int(texture->width);
  info.height = int(texture->height);
  return info;
}

Result<AssetInfo> inspectMeasured(std::string_view bytes) {
  auto table = readMerl(bytes);
  if (!table) return table.takeError();
  AssetInfo info;
  info.kind = AssetKind::Measured;
  info.format = AssetFormat::Merl;
  info.measuredBins = table->validBins;
  return info;
}

Result<AssetInfo> inspectEnvironment(std::string_view bytes, const AssetLimits& limits) {
  EnvironmentSource source;
  auto env = decodeEnvironmentImage(bytes, limits, "inspected", source);
  if (!env) return env.takeError();
  AssetInfo info;
  info.kind = AssetKind::Environment;
  info.format = source.format;
  info.layout = source.layout;
  info.width = source.width;
  info.height = source.height;
  return info;
}

}  // namespace

Result<AssetInfo> inspectAsset(std::string_view bytes, AssetKind kind, const AssetLimits& limits) {
  if (bytes.size() > limits.maxBytes)
    return makeError(ErrorCode::InvalidArgument, "the file is " + std::to_string(bytes.size()) +
                                                     " bytes; the limit is " + std::to_string(limits.maxBytes) +
                                                     " bytes");
  auto format = sniffAssetFormat(bytes);
  if (!format)
    return makeError(ErrorCode::InvalidArgument,
                     std::string("unrecognised file: expected ") + kindDescription(kind) +
                         ", but the content matches none of OBJ, PNG, JPEG, HDR, EXR or MERL");
  if (!kindAccepts(kind, *format))
    return makeError(ErrorCode::InvalidArgument, std::string("mislabelled: the file is ") + formatDescription(*format) +
                                                     ", not " + kindDescription(kind));
  switch (kind) {
    case AssetKind::Mesh: return inspectMesh(bytes, limits);
    case AssetKind::Texture: return inspectTexture(bytes, *format, limits);
    case AssetKind::Measured: return inspectMeasured(bytes);
    default: return inspectEnvironment(bytes, limits);
  }
}

}  // namespace brdfa
