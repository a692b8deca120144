// Environments: the built-ins, and files (equirectangular HDR and EXR, LDR cross cube maps)
// converted to the internal cube map. Inputs are made in memory by independent writers.
#include <gtest/gtest.h>

#include <glm/glm.hpp>
#include <glm/gtc/packing.hpp>

#include <tinyexr.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#include "assets/environment_maps.h"
#include "assets/equirect.h"
#include "assets/exr_decode.h"
#include "assets/image_decode.h"
#include "image_test_encoders.h"

namespace brdfa {
namespace {

using namespace testing;  // the image encoders

constexpr double kPi = 3.14159265358979323846;

glm::vec3 texel(const EnvironmentData& env, int face, uint32_t x, uint32_t y) {
  size_t i = ((size_t(face) * env.faceSize + y) * env.faceSize + x) * 4;
  return {env.texels[i], env.texels[i + 1], env.texels[i + 2]};
}

glm::vec3 texelDirection(int face, uint32_t x, uint32_t y, uint32_t size) {
  float d[3];
  cubeTexelDirection(face, x, y, size, d);
  return {d[0], d[1], d[2]};
}

// Calls fn(face, x, y) for every texel of a cube of `size`.
void forEachTexel(uint32_t size, const std::function<void(int, uint32_t, uint32_t)>& fn) {
  for (int face = 0; face < 6; ++face)
    for (uint32_t y = 0; y < size; ++y)
      for (uint32_t x = 0; x < size; ++x) fn(face, x, y);
}

// Irradiance at a surface with normal n: the sum over texels of L cos(theta) d(omega), the
// texel solid angles exact.
double irradiance(const EnvironmentData& env, const glm::vec3& n) {
  double sum = 0;
  forEachTexel(env.faceSize, [&](int face, uint32_t x, uint32_t y) {
    double cosine = glm::dot(n, texelDirection(face, x, y, env.faceSize));
    if (cosine > 0) sum += texel(env, face, x, y).g * cosine * cubeTexelSolidAngle(x, y, env.faceSize);
  });
  return sum;
}

struct Brightest {
  int face = -1;
  uint32_t x = 0, y = 0;
  glm::vec3 direction{0};
};

Brightest brightestTexel(const EnvironmentData& env) {
  Brightest best;
  float value = -1;
  forEachTexel(env.faceSize, [&](int face, uint32_t x, uint32_t y) {
    float v = texel(env, face, x, y).r;
    if (v > value) {
      value = v;
      best = {face, x, y, texelDirection(face, x, y, env.faceSize)};
    }
  });
  return best;
}

// The radiance-weighted mean direction of the texels brighter than `threshold`.
glm::vec3 brightCentroid(const EnvironmentData& env, float threshold) {
  glm::vec3 sum(0.0f);
  forEachTexel(env.faceSize, [&](int face, uint32_t x, uint32_t y) {
    float v = texel(env, face, x, y).r;
    if (v > threshold) sum += v * texelDirection(face, x, y, env.faceSize);
  });
  return glm::normalize(sum);
}

double angleDegrees(const glm::vec3& a, const glm::vec3& b) {
  return glm::degrees(std::acos(glm::clamp(glm::dot(glm::normalize(a), glm::normalize(b)), -1.0f, 1.0f)));
}

// A linear RGB equirect image whose pixel (x, y) is fn(x, y).
std::vector<float> equirectImage(int w, int h, const std::function<glm::vec3(int, int)>& fn) {
  std::vector<float> rgb(size_t(w) * h * 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      glm::vec3 v = fn(x, y);
      for (int c = 0; c < 3; ++c) rgb[(size_t(y) * w + x) * 3 + c] = v[c];
    }
  return rgb;
}

Result<EnvironmentData> decode(const std::string& bytes, std::string* layout = nullptr) {
  return decodeEnvironment(bytes, AssetLimits{}, "test", layout);
}

EnvironmentData decodeOk(const std::string& bytes, std::string* layout = nullptr) {
  auto env = decode(bytes, layout);
  EXPECT_TRUE(env.ok()) << env.error().message;
  return env.ok() ? env.value() : EnvironmentData{};
}

void expectInvalid(const Result<EnvironmentData>& r, const std::string& needle) {
  ASSERT_FALSE(r.ok()) << "expected an error mentioning '" << needle << "'";
  EXPECT_EQ(r.error().code, ErrorCode::InvalidArgument);
  EXPECT_NE(r.error().message.find(needle), std::string::npos) << r.error().message;
}

void expectFiniteAndInRange(const EnvironmentData& env, float lo, float hi) {
  for (size_t i = 0; i < env.texels.size(); ++i) {
    float v = env.texels[i];
    ASSERT_TRUE(std::isfinite(v)) << "texel value " << i;
    ASSERT_GE(v, lo) << "texel value " << i;
    ASSERT_LE(v, hi) << "texel value " << i;
  }
}

// ---- built-in environments ----------------------------------------------------------------

TEST(EnvironmentBuiltins, NamesAndShapes) {
  EXPECT_EQ(builtinEnvironmentNames(), (std::vector<std::string>{"furnace", "sky", "studio", "cornell"}));
  for (const std::string& name : builtinEnvironmentNames()) {
    auto env = makeBuiltinEnvironment(name);
    ASSERT_TRUE(env.ok()) << name;
    EXPECT_EQ(env->name, name);
    EXPECT_EQ(env->texels.size(), size_t(6) * env->faceSize * env->faceSize * 4) << name;
    expectFiniteAndInRange(*env, 0.0f, 1000.0f);
    EXPECT_EQ(env->constant, name == "furnace");
  }
  EXPECT_EQ(makeBuiltinEnvironment("studio")->faceSize, 256u);
  EXPECT_EQ(makeBuiltinEnvironment("cornell")->faceSize, 256u);
  EXPECT_EQ(makeBuiltinEnvironment("nowhere").error().code, ErrorCode::NotFound);
}

// The radiance of the texel whose centre is nearest `direction`.
glm::vec3 radianceToward(const EnvironmentData& env, glm::vec3 direction) {
  direction = glm::normalize(direction);
  float d[3] = {direction.x, direction.y, direction.z};
  int face;
  float s, t;
  cubeFaceCoords(d, face, s, t);
  auto index = [&](float c) {
    return std::min(env.faceSize - 1, static_cast<uint32_t>((c + 1.0f) * 0.5f * env.faceSize));
  };
  return texel(env, face, index(s), index(t));
}

TEST(EnvironmentBuiltins, StudioHasThreeSharpLightsOverADimSurround) {
  auto env = makeBuiltinEnvironment("studio");
  ASSERT_TRUE(env.ok());
  EXPECT_NEAR(radianceToward(*env, {0, -1, 0}).g, 0.03f, 1e-4f);  // floor: surround
  EXPECT_NEAR(radianceToward(*env, {0, 0, -1}).g, 0.03f, 1e-4f);  // straight ahead: surround
  glm::vec3 key = radianceToward(*env, {-0.55f, 0.55f, 0.63f});
  glm::vec3 fill = radianceToward(*env, {0.85f, 0.10f, 0.50f});
  glm::vec3 rim = radianceToward(*env, {0.15f, 0.45f, -0.88f});
  EXPECT_NEAR(key.g, 13.3f, 0.05f);
  EXPECT_NEAR(fill.g, 2.2f, 0.01f);
  EXPECT_NEAR(rim.g, 9.0f, 0.01f);
  // Sharp: walking out of the key light, radiance falls from the light's value to the
  // surround's within two texels (one partly covered texel from the antialiasing).
  int texelsInTransition = 0;
  glm::vec3 centre = glm::normalize(glm::vec3(-0.55f, 0.55f, 0.63f));
  glm::vec3 right = glm::normalize(glm::cross(centre, glm::vec3(0, 1, 0)));
  for (int step = 0; step < 400; ++step) {
    glm::vec3 d = centre + right * (0.2f + 0.0005f * step);  // crosses the edge at 0.32
    float v = radianceToward(*env, d).g;
    if (v > 0.05f && v < 13.0f) ++texelsInTransition;
  }
  // Steps are ~ 1/4 texel here, so 8 steps span about two texels.
  EXPECT_GT(texelsInTransition, 0);
  EXPECT_LE(texelsInTransition, 12);
}

TEST(EnvironmentBuiltins, CornellRoomWallsAndCeilingLight) {
  auto env = makeBuiltinEnvironment("cornell");
  ASSERT_TRUE(env.ok());
  glm::vec3 left = radianceToward(*env, {-1, 0, 0}), right = radianceToward(*env, {1, 0, 0});
  glm::vec3 back = radianceToward(*env, {0, 0, -1}), floor = radianceToward(*env, {0, -1, 0});
  EXPECT_GT(left.r, 3 * left.g);        // red wall on the default camera's left (-X)
  EXPECT_GT(right.g, 2 * right.r);      // green wall on its right (+X)
  EXPECT_NEAR(back.r, floor.r, 1e-3f);  // white walls all alike
  EXPECT_NEAR(back.r, 0.725f * 0.09f * 17.0f / kPi, 2e-3f);
  glm::vec3 light = radianceToward(*env, {0, 1, 0});
  EXPECT_NEAR(light.r, 17.0f, 0.02f);
  EXPECT_NEAR(light.g, 12.0f, 0.02f);
  EXPECT_NEAR(light.b, 4.0f, 0.01f);
  // The light is a square on the ceiling of half-size 0.25 at height 1: just outside it, wall.
  EXPECT_LT(radianceToward(*env, {0.3f, 1, 0}).r, 1.0f);
  EXPECT_LT(radianceToward(*env, {0, 1, -0.3f}).r, 1.0f);
  EXPECT_GT(radianceToward(*env, {0.2f, 1, 0.2f}).r, 16.0f);
}

TEST(EnvironmentMaths, TexelSolidAnglesSumToTheSphere) {
  for (uint32_t size : {1u, 7u, 64u}) {
    double sum = 0;
    for (uint32_t y = 0; y < size; ++y)
      for (uint32_t x = 0; x < size; ++x) sum += cubeTexelSolidAngle(x, y, size);
    EXPECT_NEAR(6 * sum, 4 * kPi, 1e-9) << size;
  }
}

TEST(EnvironmentMaths, FaceCoordsInvertFaceDirections) {
  forEachTexel(8, [](int face, uint32_t x, uint32_t y) {
    float d[3], s, t;
    int back;
    cubeTexelDirection(face, x, y, 8, d);
    cubeFaceCoords(d, back, s, t);
    EXPECT_EQ(back, face);
    EXPECT_NEAR(s, 2 * (x + 0.5f) / 8 - 1, 1e-5f);
    EXPECT_NEAR(t, 2 * (y + 0.5f) / 8 - 1, 1e-5f);
  });
}

// ---- equirectangular HDR and EXR ----------------------------------------------------------

TEST(EnvironmentEquirect, FaceSizeIsAQuarterOfTheWidthAsAPowerOfTwo) {
  EXPECT_EQ(equirectFaceSize(2048), 512u);
  EXPECT_EQ(equirectFaceSize(1024), 256u);
  EXPECT_EQ(equirectFaceSize(1000), 256u);
  EXPECT_EQ(equirectFaceSize(512), 128u);
  EXPECT_EQ(equirectFaceSize(100), 32u);
  EXPECT_EQ(equirectFaceSize(8), 16u);
  EXPECT_EQ(equirectFaceSize(16384), 1024u);
}

TEST(EnvironmentEquirect, UpperHemisphereGivesTheExpectedIrradiance) {
  // Radiance 1 above the horizon and 0 below: E(n) = pi (1 + n.y) / 2 (the integral of cos
  // over the part of n's hemisphere above the horizon).
  const int w = 512, h = 256;
  auto rgb = equirectImage(w, h, [&](int, int y) { return glm::vec3(y < h / 2 ? 1.0f : 0.0f); });
  std::string layout;
  EnvironmentData env = decodeOk(encodeHdr(w, h, rgb), &layout);
  EXPECT_EQ(layout, "equirect");
  ASSERT_EQ(env.faceSize, 128u);
  for (glm::vec3 n : {glm::vec3(0, 1, 0), glm::vec3(1, 0, 0), glm::vec3(0, 0, -1), glm::vec3(1, 1, 1),
                      glm::vec3(-0.3f, 0.5f, 0.8f), glm::vec3(0.4f, -0.6f, 0.2f), glm::vec3(-1, -1, 0)}) {
    n = glm::normalize(n);
    double expected = kPi * (1 + n.y) / 2;
    EXPECT_NEAR(irradiance(env, n), expected, 0.005 * expected) << n.x << " " << n.y << " " << n.z;
  }
  EXPECT_NEAR(irradiance(env, {0, -1, 0}), 0.0, 0.005 * kPi);
}

// Values that RGBE (8-bit mantissas under a shared exponent) and half floats both hold
// exactly: multiples of 1/32 below 8.
std::vector<float> exactlyRepresentablePattern(int w, int h) {
  return equirectImage(
      w, h, [](int x, int y) { return glm::vec3(float(x % 16) / 8, float(y % 32) / 16, float((x + y) % 8) / 4); });
}

TEST(EnvironmentEquirect, ExrGivesTheSameCubeAsHdr) {
  const int w = 128, h = 64;
  auto rgb = exactlyRepresentablePattern(w, h);
  EnvironmentData fromHdr = decodeOk(encodeHdr(w, h, rgb));
  ASSERT_EQ(fromHdr.faceSize, 32u);
  std::string layout;
  EnvironmentData fromHalfExr = decodeOk(encodeExr(w, h, rgb, true), &layout);
  EXPECT_EQ(layout, "equirect");
  EXPECT_EQ(fromHdr.texels, fromHalfExr.texels);
  EXPECT_EQ(fromHdr.texels, decodeOk(encodeExr(w, h, rgb, false, TINYEXR_COMPRESSIONTYPE_PIZ)).texels);
  // OpenEXR's own writer, with the lossless codecs and layouts tinyexr does not write: tiles,
  // several parts (part 0 is read), an alpha channel (ignored).
  struct Case {
    const char* label;
    OpenExrOptions options;
  };
  const Case cases[] = {{"PIZ half", {.compression = 4}},
                        {"ZIP float tiled", {.compression = 3, .half = false, .tiled = true}},
                        {"RLE half multi-part", {.compression = 1, .parts = 2}},
                        {"ZIPS float tiled multi-part", {.compression = 2, .half = false, .tiled = true, .parts = 2}},
                        {"PXR24 half", {.compression = 5}},  // lossless for half channels
                        {"NONE float", {.compression = 0, .half = false}}};
  for (const Case& c : cases)
    EXPECT_EQ(fromHdr.texels, decodeOk(encodeExrWithOpenExr(w, h, rgb, c.options)).texels) << c.label;
}

// The largest relative difference between two images of the same size, per value, over values
// of at least `floor` (smaller ones compared to `floor`).
double largestRelativeError(const std::vector<float>& a, const std::vector<float>& b, float floor) {
  EXPECT_EQ(a.size(), b.size());
  double worst = 0;
  for (size_t i = 0; i < std::min(a.size(), b.size()); ++i)
    worst = std::max(worst, std::abs(double(a[i]) - b[i]) / std::max(std::abs(b[i]), floor));
  return worst;
}

TEST(EnvironmentEquirect, LossyExrCompressionsDecode) {
  // The codecs of the DWA family (blender-data's worlds are DWAB) and B44 are lossy: a smooth
  // image comes back close, and as a cube close to the same image from HDR.
  const int w = 256, h = 128;
  auto rgb = equirectImage(w, h, [&](int x, int y) {
    return glm::vec3(0.2f + 2.0f * x / w, 0.5f + 0.3f * std::sin(y / 8.0f), 1.0f + 0.5f * std::cos(x / 16.0f));
  });
  EnvironmentData fromHdr = decodeOk(encodeHdr(w, h, rgb));
  for (int compression : {9, 8, 6, 7}) {  // DWAB, DWAA, B44, B44A
    for (bool tiled : {false, true}) {
      SCOPED_TRACE("compression " + std::to_string(compression) + (tiled ? ", tiled" : ""));
      std::string file = encodeExrWithOpenExr(w, h, rgb, {.compression = compression, .tiled = tiled});
      auto image = decodeExr(file, [](int, int) { return Result<void>(); });
      ASSERT_TRUE(image.ok()) << image.error().message;
      ASSERT_EQ(image->width, w);
      ASSERT_EQ(image->height, h);
      EXPECT_LT(largestRelativeError(image->rgb, rgb, 0.1f), 0.03);
      EnvironmentData env = decodeOk(file);
      ASSERT_EQ(env.faceSize, fromHdr.faceSize);
      double worst = 0;
      for (size_t i = 0; i < env.texels.size(); ++i)
        worst = std::max(worst, double(std::abs(env.texels[i] - fromHdr.texels[i])));
      EXPECT_LT(worst, 0.05);
    }
  }
}

TEST(EnvironmentEquirect, GreyExrIsReadAsGrey) {
  const int w = 64, h = 32;
  auto rgb = equirectImage(w, h, [](int x, int y) { return glm::vec3(9.0f, float(x + y) / 16, 9.0f); });
  auto image = decodeExr(encodeExrWithOpenExr(w, h, rgb, {.compression = 3, .grey = true}),
                         [](int, int) { return Result<void>(); });
  ASSERT_TRUE(image.ok()) << image.error().message;
  for (size_t i = 0; i < size_t(w) * h; ++i)
    for (int c = 0; c < 3; ++c) ASSERT_EQ(image->rgb[i * 3 + c], rgb[i * 3 + 1]) << i << " " << c;
}

// Offset of the value of the first header attribute `name` of `type` at or after `from`
// (OpenEXR file layout: name, type, 4-byte size, value).
size_t exrAttribute(const std::string& exr, const std::string& name, const std::string& type, size_t from = 0) {
  std::string key = name + '\0' + type + '\0';
  size_t at = exr.find(key, from);
  EXPECT_NE(at, std::string::npos) << name;
  return at == std::string::npos ? exr.size() : at + key.size() + 4;
}

void putInt32(std::string& bytes, size_t at, int32_t value) {
  for (int i = 0; i < 4; ++i) bytes.at(at + i) = char(uint32_t(value) >> (8 * i));
}

TEST(EnvironmentEquirect, ExrSizeIsCheckedFromTheHeader) {
  // Headers declaring more than the file holds are refused before OpenEXR allocates for them.
  auto rgb = exactlyRepresentablePattern(64, 32);
  std::string exr = encodeExr(64, 32, rgb, true);
  size_t window = exrAttribute(exr, "dataWindow", "box2i");  // min x, min y, max x, max y
  std::string huge = exr;
  putInt32(huge, window + 8, (1 << 15) - 1);
  putInt32(huge, window + 12, (1 << 14) - 1);
  expectInvalid(decode(huge), "32768x16384");
  std::string implausible = exr;
  putInt32(implausible, window, INT32_MIN);
  putInt32(implausible, window + 8, INT32_MAX);
  expectInvalid(decode(implausible), "implausibly large");
  std::string inverted = exr;
  putInt32(inverted, window + 12, -5);
  expectInvalid(decode(inverted), "empty");
  std::string tiled = encodeExrWithOpenExr(64, 32, rgb, {.compression = 3, .tiled = true});
  size_t tiles = exrAttribute(tiled, "tiles", "tiledesc");  // x size, y size, mode
  putInt32(tiled, tiles, 1 << 20);
  putInt32(tiled, tiles + 4, 1 << 20);
  expectInvalid(decode(tiled), "tiles are larger than its image");
  // A window within the pixel limit but with more lines (chunks, with ZIPS) than the file has
  // room for in its chunk table.
  std::string zips = encodeExr(64, 32, std::vector<float>(64 * 32 * 3, 1.0f), true, TINYEXR_COMPRESSIONTYPE_ZIPS);
  ASSERT_LT(zips.size(), 2048u * 8);
  putInt32(zips, exrAttribute(zips, "dataWindow", "box2i") + 8, 4095);
  putInt32(zips, exrAttribute(zips, "dataWindow", "box2i") + 12, 2047);
  expectInvalid(decode(zips), "cannot fit");
  // The same in the second part of a multi-part file, which is not read but whose table
  // OpenEXR allocates.
  std::string parts = encodeExrWithOpenExr(64, 32, rgb, {.compression = 3, .parts = 2});
  ASSERT_TRUE(decode(parts).ok());
  size_t second = exrAttribute(parts, "dataWindow", "box2i", exrAttribute(parts, "dataWindow", "box2i"));
  putInt32(parts, second + 12, (1 << 24) - 1);
  expectInvalid(decode(parts), "cannot fit");
  // An attribute of a type OpenEXR does not know, declaring 1.75 GiB: OpenEXR would allocate them.
  std::string opaque = exr;
  size_t ratio = exrAttribute(opaque, "pixelAspectRatio", "float");
  opaque.replace(ratio - 7 - 4, 5, "flxat");
  putInt32(opaque, ratio - 4, 0x70000000);
  expectInvalid(decode(opaque), "an attribute runs past the end of the file");
}

TEST(EnvironmentEquirect, DeepExrAndMissingColourChannelsAreRefused) {
  auto rgb = exactlyRepresentablePattern(32, 16);
  expectInvalid(decode(encodeExrWithOpenExr(32, 16, rgb, {.deep = true})), "deep EXR images");
  // Renaming channel R to S (the channel list stays sorted: B, G, S).
  std::string exr = encodeExr(32, 16, rgb, true);
  size_t red = exrAttribute(exr, "channels", "chlist") + 2 * 18;  // B and G take 18 bytes each
  ASSERT_EQ(exr.substr(red, 2), std::string("R\0", 2));
  exr[red] = 'S';
  expectInvalid(decode(exr), "no R, G and B channels (it has: B, G, S)");
}

// The equirect pixel holding unit direction d, by the documented mapping
// u = 0.5 + atan2(d.x, -d.z) / (2 pi), v = acos(d.y) / pi.
void equirectPixel(glm::vec3 d, int w, int h, int& x, int& y) {
  d = glm::normalize(d);
  double u = 0.5 + std::atan2(d.x, -d.z) / (2 * kPi), v = std::acos(d.y) / kPi;
  x = std::min(w - 1, int(u * w));
  y = std::min(h - 1, int(v * h));
}

TEST(EnvironmentEquirect, BrightSpotLandsInTheRightTexel) {
  const int w = 256, h = 128;
  struct Case {
    glm::vec3 direction;
    int face;
  };
  const Case cases[] = {{{0.1f, 0.2f, -1}, 5}, {{1, 0.3f, 0.2f}, 0},  {{-1, -0.2f, 0.4f}, 1},
                        {{0.2f, 1, -0.3f}, 2}, {{0.3f, -1, 0.1f}, 3}, {{-0.25f, 0.1f, 1}, 4}};
  for (const Case& c : cases) {
    int px, py;
    equirectPixel(c.direction, w, h, px, py);
    auto rgb = equirectImage(w, h, [&](int x, int y) { return glm::vec3(x == px && y == py ? 1000.0f : 0.0f); });
    EnvironmentData env = decodeOk(encodeHdr(w, h, rgb));
    Brightest b = brightestTexel(env);
    EXPECT_EQ(b.face, c.face) << c.direction.x << " " << c.direction.y << " " << c.direction.z;
    EXPECT_LT(angleDegrees(b.direction, c.direction), 3.0);
  }
  // The image centre is what the default camera sees: the centre of face -Z.
  auto centre = equirectImage(w, h, [&](int x, int y) {
    return glm::vec3((x == w / 2 - 1 || x == w / 2) && (y == h / 2 - 1 || y == h / 2) ? 1000.0f : 0.0f);
  });
  Brightest b = brightestTexel(decodeOk(encodeHdr(w, h, centre)));
  EXPECT_EQ(b.face, 5);
  EXPECT_LT(angleDegrees(b.direction, {0, 0, -1}), 2.0);
}

TEST(EnvironmentEquirect, NegativeValuesAreClampedAndHugeOnesKept) {
  const int w = 64, h = 32;
  auto rgb = equirectImage(
      w, h, [](int x, int y) { return x == 10 && y == 10 ? glm::vec3(1e6f) : glm::vec3(x == 20 ? -5.0f : 0.5f); });
  EnvironmentData fromExr = decodeOk(encodeExr(w, h, rgb, false));
  expectFiniteAndInRange(fromExr, 0.0f, 1e6f);
  EXPECT_GT(brightestTexel(fromExr).direction.y, 0.0f);
  // Far above the half-float range: the spot's energy must survive the cube.
  float brightest = 0;
  for (size_t i = 0; i < fromExr.texels.size(); i += 4) brightest = std::max(brightest, fromExr.texels[i]);
  EXPECT_GT(brightest, 65504.0f);
  HalfCube packed = packHalfCube(fromExr);
  EXPECT_GE(packed.scale, brightest / 65504.0f);
  EXPECT_LT(packed.scale, 2 * brightest / 65504.0f);  // the smallest power of two that fits
  for (size_t i = 0; i < packed.texels.size(); ++i) {
    const float v = glm::unpackHalf1x16(packed.texels[i]) * (i % 4 == 3 ? 1.0f : packed.scale);
    ASSERT_TRUE(std::isfinite(v)) << i;
    const float want = fromExr.texels[i];
    ASSERT_NEAR(v, want, want * 1e-3f + 1e-4f * packed.scale) << i;
  }
  // RGBE holds neither negatives nor non-finite values; a huge one is kept.
  auto positive = equirectImage(w, h, [](int x, int y) { return glm::vec3(x == 10 && y == 10 ? 1e6f : 0.5f); });
  expectFiniteAndInRange(decodeOk(encodeHdr(w, h, positive)), 0.0f, 1e6f);
  EXPECT_EQ(packHalfCube(decodeOk(encodeHdr(w, h, rgb))).scale > 1.0f, true);
  EXPECT_EQ(packHalfCube(*makeBuiltinEnvironment("sky")).scale, 1.0f);  // in range: stored as before
}

TEST(EnvironmentEquirect, NonFiniteExrValuesAreRefused) {
  const int w = 16, h = 8;
  for (float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()})
    for (bool half : {false, true}) {
      auto rgb =
          equirectImage(w, h, [&](int x, int y) { return glm::vec3(0.5f, x == 3 && y == 2 ? bad : 0.5f, 0.5f); });
      auto env = decode(encodeExr(w, h, rgb, half));
      expectInvalid(env, "non-finite");
      expectInvalid(env, "(3, 2)");
    }
}

TEST(EnvironmentEquirect, WrongAspectAndPixelLimitAreRefused) {
  expectInvalid(decode(encodeHdr(60, 40, equirectImage(60, 40, [](int, int) { return glm::vec3(1); }))), "60x40");
  expectInvalid(decode(encodeExr(30, 20, equirectImage(30, 20, [](int, int) { return glm::vec3(1); }), true)),
                "width = 2 x height");
  AssetLimits limits;
  limits.maxPixels = 64 * 32 - 1;
  auto rgb = equirectImage(64, 32, [](int, int) { return glm::vec3(1); });
  expectInvalid(decodeEnvironment(encodeHdr(64, 32, rgb), limits, "t", nullptr), "the limit is 2047 pixels");
  expectInvalid(decodeEnvironment(encodeExr(64, 32, rgb, true), limits, "t", nullptr), "64x32");
}

std::string smoothHdr(int w, int h) {
  return encodeHdr(w, h, equirectImage(w, h, [&](int x, int y) {
                     return glm::vec3(0.2f + float(x) / w, 0.5f + 0.3f * std::sin(float(y)), 1.0f);
                   }));
}

TEST(EnvironmentEquirect, TruncatedAndCorruptHdrAreRefused) {
  std::string hdr = smoothHdr(64, 32);
  ASSERT_TRUE(decode(hdr).ok());
  expectInvalid(decode(hdr.substr(0, hdr.size() / 2)), "truncated");
  std::string flat = smoothHdr(4, 2);  // narrower than 8: flat (not run-length) pixels
  ASSERT_TRUE(decode(flat).ok());
  expectInvalid(decode(flat.substr(0, flat.size() - 5)), "truncated");
  // Garbage over the pixel data: 0xFF as a count is a run of 127, longer than a 64-pixel
  // scanline. (RGBE has no checksum: garbage inside a literal run is just other pixels.)
  std::string garbage = hdr;
  for (size_t i = hdr.size() / 2; i < hdr.size() / 2 + 300; ++i) garbage[i] = char(0xFF);
  expectInvalid(decode(garbage), "HDR");
  std::string format = hdr;
  format.replace(format.find("32-bit_rle_rgbe"), 15, "32-bit_rle_xyze");
  expectInvalid(decode(format), "stb_image");
  std::string resolution = hdr;
  resolution.replace(resolution.find("+X"), 2, "+Q");
  expectInvalid(decode(resolution), "stb_image");
  expectInvalid(decode("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 32 +X 64\n"), "truncated");
}

std::string smoothExr(int w, int h) {
  return encodeExr(w, h,
                   equirectImage(w, h,
                                 [&](int x, int y) {
                                   return glm::vec3(0.2f + float(x) / w, 0.5f + 0.3f * std::sin(float(y) / 4), 1.0f);
                                 }),
                   true);
}

// Overwrites 64 bytes at `at` (a fraction of the size) with garbage.
std::string scrambled(std::string bytes, double at = 0.75) {
  size_t start = size_t(bytes.size() * at);
  for (size_t i = start; i < std::min(bytes.size(), start + 64); ++i) bytes[i] = char(0x5A ^ (i * 31));
  return bytes;
}

// OpenEXR reports damaged files by throwing; the decoder turns that into its reason.
TEST(EnvironmentEquirect, TruncatedAndCorruptExrAreRefused) {
  std::string exr = smoothExr(128, 64);
  ASSERT_TRUE(decode(exr).ok());
  expectInvalid(decode(exr.substr(0, exr.size() / 2)), "truncated");
  expectInvalid(decode(scrambled(exr)), "Data decompression (zlib) failed");
  auto rgb = equirectImage(128, 64, [](int x, int) { return glm::vec3(float(x / 16)); });  // runs for RLE
  std::string rle = encodeExr(128, 64, rgb, true, TINYEXR_COMPRESSIONTYPE_RLE);
  ASSERT_TRUE(decode(rle).ok());
  expectInvalid(decode(scrambled(rle)), "Data decoding (rle) failed");
  std::string plain = encodeExr(128, 64, rgb, false, TINYEXR_COMPRESSIONTYPE_NONE);
  ASSERT_TRUE(decode(plain).ok());
  expectInvalid(decode(plain.substr(0, plain.size() - 10)), "truncated");
  std::string zips = encodeExr(128, 64, rgb, true, TINYEXR_COMPRESSIONTYPE_ZIPS);
  ASSERT_TRUE(decode(zips).ok());
  expectInvalid(decode(scrambled(zips)), "EXR");
  std::string header = exr;
  for (size_t i = 8; i < 40; ++i) header[i] = char(0xEE);
  expectInvalid(decode(header), "EXR");
  expectInvalid(decode(exr.substr(0, 6)), "EXR");
}

// Every layout and codec, cut short anywhere or with garbage anywhere: refused, or (garbage in
// a codec without checks) decoded to whatever the garbage says; never a crash or a leak (the
// unit tests also run under valgrind).
TEST(EnvironmentEquirect, DamagedExrOfEveryKindIsRefusedSafely) {
  const int w = 64, h = 32;
  auto rgb =
      equirectImage(w, h, [&](int x, int y) { return glm::vec3(0.2f + float(x) / w, 0.5f, 1.0f + float(y) / h); });
  const OpenExrOptions kinds[] = {{.compression = 9},
                                  {.compression = 8, .tiled = true},
                                  {.compression = 4, .half = false},
                                  {.compression = 6, .parts = 2},
                                  {.compression = 5, .half = false, .tiled = true},
                                  {.compression = 3, .grey = true}};
  for (const OpenExrOptions& kind : kinds) {
    std::string exr = encodeExrWithOpenExr(w, h, rgb, kind);
    SCOPED_TRACE("compression " + std::to_string(kind.compression) + (kind.tiled ? ", tiled" : "") +
                 (kind.parts > 1 ? ", multi-part" : ""));
    ASSERT_TRUE(decode(exr).ok());
    for (int part = 1; part < 16; ++part) {
      auto env = decode(exr.substr(0, exr.size() * part / 16));
      ASSERT_FALSE(env.ok()) << part << "/16";
      EXPECT_EQ(env.error().code, ErrorCode::InvalidArgument) << env.error().message;
    }
    for (double at : {0.02, 0.1, 0.3, 0.5, 0.7, 0.9}) {
      auto env = decode(scrambled(exr, at));
      EXPECT_TRUE(env.ok() || env.error().code == ErrorCode::InvalidArgument) << at << ": " << env.error().message;
    }
  }
}

TEST(EnvironmentEquirect, UnrecognisedBytesAreRefused) {
  expectInvalid(decode("hello"), "not an HDR, EXR, PNG or JPEG image");
  expectInvalid(decode(""), "not an HDR, EXR, PNG or JPEG image");
}

// ---- horizontal-cross cube maps -----------------------------------------------------------

// The test's own reading of the usual cross, written independently of the decoder: what a
// viewer at the centre sees on each face, as the face's centre direction and the world
// directions of the picture's right and down. The default camera looks down -Z with +Y up, so
// the cross's front face "+Z" is world -Z, and its right, "+X", is world +X.
struct CrossFace {
  const char* label;
  int column, row;
  glm::vec3 centre, right, down;
};
const CrossFace kCross[6] = {
    {"+Y", 1, 0, {0, 1, 0}, {1, 0, 0}, {0, 0, -1}},  {"-X", 0, 1, {-1, 0, 0}, {0, 0, -1}, {0, -1, 0}},
    {"+Z", 1, 1, {0, 0, -1}, {1, 0, 0}, {0, -1, 0}}, {"+X", 2, 1, {1, 0, 0}, {0, 0, 1}, {0, -1, 0}},
    {"-Z", 3, 1, {0, 0, 1}, {-1, 0, 0}, {0, -1, 0}}, {"-Y", 1, 2, {0, -1, 0}, {1, 0, 0}, {0, 0, 1}},
};

glm::vec3 crossPixelDirection(const CrossFace& f, int col, int row, int n) {
  float s = (2.0f * col + 1) / n - 1, t = (2.0f * row + 1) / n - 1;
  return glm::normalize(f.centre + s * f.right + t * f.down);
}

// An sRGB cross of faces n x n showing linear radiance fn(direction); unused corners magenta.
std::vector<uint8_t> crossImage(int n, const std::function<glm::vec3(glm::vec3)>& fn) {
  const int w = 4 * n, h = 3 * n;
  std::vector<uint8_t> px(size_t(w) * h * 3);
  for (size_t i = 0; i < px.size(); i += 3) {
    px[i] = 255;
    px[i + 1] = 0;
    px[i + 2] = 255;
  }
  for (const CrossFace& f : kCross)
    for (int row = 0; row < n; ++row)
      for (int col = 0; col < n; ++col) {
        glm::vec3 L = fn(crossPixelDirection(f, col, row, n));
        uint8_t* p = &px[(size_t(f.row * n + row) * w + f.column * n + col) * 3];
        for (int c = 0; c < 3; ++c) p[c] = linearToSrgbByte(L[c]);
      }
  return px;
}

glm::vec3 smoothRadiance(glm::vec3 d) { return glm::vec3(0.5f) + 0.45f * d; }

TEST(EnvironmentCross, TheTestsCrossIsTheUsualUnmirroredLayout) {
  const int n = 16;
  const float tolerance = 2.5f * glm::degrees(2.0f / n);
  for (const CrossFace& f : kCross) {
    // Unmirrored for a viewer inside: right = forward x up, with up = -down.
    glm::vec3 expectedRight = glm::cross(f.centre, -f.down);
    EXPECT_EQ(f.right, expectedRight) << f.label;
  }
  // Neighbouring pixels across every edge the cross shows are neighbouring directions.
  auto face = [](const char* label) -> const CrossFace& {
    for (const CrossFace& f : kCross)
      if (std::string(f.label) == label) return f;
    return kCross[0];
  };
  const char* strip[5] = {"-X", "+Z", "+X", "-Z", "-X"};  // the middle row wraps around
  for (int i = 0; i < 4; ++i)
    for (int row = 0; row < n; ++row)
      EXPECT_LT(angleDegrees(crossPixelDirection(face(strip[i]), n - 1, row, n),
                             crossPixelDirection(face(strip[i + 1]), 0, row, n)),
                tolerance)
          << strip[i] << " | " << strip[i + 1];
  for (int col = 0; col < n; ++col) {
    EXPECT_LT(angleDegrees(crossPixelDirection(face("+Y"), col, n - 1, n), crossPixelDirection(face("+Z"), col, 0, n)),
              tolerance);
    EXPECT_LT(angleDegrees(crossPixelDirection(face("+Z"), col, n - 1, n), crossPixelDirection(face("-Y"), col, 0, n)),
              tolerance);
  }
}

TEST(EnvironmentCross, EveryTexelShowsWhatTheCrossShowsThatWay) {
  const int n = 32;
  std::string layout;
  EnvironmentData env = decodeOk(encodePng(4 * n, 3 * n, 3, crossImage(n, smoothRadiance)), &layout);
  EXPECT_EQ(layout, "cross");
  ASSERT_EQ(env.faceSize, uint32_t(n));
  float worst = 0;
  forEachTexel(env.faceSize, [&](int face, uint32_t x, uint32_t y) {
    glm::vec3 expected = smoothRadiance(texelDirection(face, x, y, env.faceSize));
    glm::vec3 error = glm::abs(texel(env, face, x, y) - expected);
    worst = std::max(worst, std::max(error.r, std::max(error.g, error.b)));
  });
  // 8-bit sRGB steps are at most ~0.009 in linear near 1; half adds ~0.0005.
  EXPECT_LT(worst, 0.01f);
}

TEST(EnvironmentCross, DecodedCubeIsContinuousAcrossFaceEdges) {
  const int n = 32;
  EnvironmentData env = decodeOk(encodePng(4 * n, 3 * n, 3, crossImage(n, smoothRadiance)));
  ASSERT_EQ(env.faceSize, uint32_t(n));
  // From each edge texel, step half a texel past the edge onto the neighbouring face.
  const float past = 1.0f + 1.0f / n;
  forEachTexel(n, [&](int face, uint32_t x, uint32_t y) {
    float s = 2 * (x + 0.5f) / n - 1, t = 2 * (y + 0.5f) / n - 1;
    for (glm::vec2 st : {glm::vec2(-past, t), glm::vec2(past, t), glm::vec2(s, -past), glm::vec2(s, past)}) {
      if (std::abs(st.x) < 1 && std::abs(st.y) < 1) continue;
      if ((st.x == -past && x != 0) || (st.x == past && x != uint32_t(n) - 1)) continue;
      if ((st.y == -past && y != 0) || (st.y == past && y != uint32_t(n) - 1)) continue;
      float d[3], ns, nt;
      int other;
      cubeFaceDirection(face, st.x, st.y, d);
      cubeFaceCoords(d, other, ns, nt);
      ASSERT_NE(other, face);
      auto index = [&](float c) { return std::min(uint32_t(n) - 1, uint32_t((c + 1) * 0.5f * n)); };
      glm::vec3 difference = glm::abs(texel(env, face, x, y) - texel(env, other, index(ns), index(nt)));
      EXPECT_LT(std::max(difference.r, std::max(difference.g, difference.b)), 0.05f)
          << "face " << face << " texel " << x << "," << y << " -> face " << other;
    }
  });
}

TEST(EnvironmentCross, FrontFaceIsWhatTheDefaultCameraSees) {
  // A bright square in the upper right of the cross's front face ("+Z") must appear upper
  // right for the default camera (at +Z looking down -Z): direction (0.5, 0.5, -1).
  const int n = 32;
  std::vector<uint8_t> px(size_t(4 * n) * 3 * n * 3, 10);
  for (int row = 6; row < 10; ++row)
    for (int col = 22; col < 26; ++col)
      for (int c = 0; c < 3; ++c) px[(size_t(n + row) * 4 * n + n + col) * 3 + c] = 255;
  EnvironmentData env = decodeOk(encodePng(4 * n, 3 * n, 3, px));
  EXPECT_EQ(brightestTexel(env).face, 5);
  EXPECT_LT(angleDegrees(brightCentroid(env, 0.5f), {0.5f, 0.5f, -1}), 0.5);
}

TEST(EnvironmentCross, JpegCrossDecodes) {
  const int n = 16;
  std::string layout;
  EnvironmentData env = decodeOk(encodeJpeg(4 * n, 3 * n, 3, crossImage(n, smoothRadiance), 95), &layout);
  EXPECT_EQ(layout, "cross");
  EXPECT_EQ(env.faceSize, uint32_t(n));
  expectFiniteAndInRange(env, 0.0f, 1.0f);
}

TEST(EnvironmentCross, WrongShapeIsRefused) {
  std::vector<uint8_t> square(100 * 100 * 3, 128);
  expectInvalid(decode(encodePng(100, 100, 3, square)), "100x100");
  expectInvalid(decode(encodeJpeg(100, 100, 3, square)), "horizontal-cross");
  std::vector<uint8_t> odd(402 * 300 * 3, 128);  // 402 / 4 is not whole
  expectInvalid(decode(encodePng(402, 300, 3, odd)), "402x300");
  AssetLimits limits;
  limits.maxPixels = 64 * 48 - 1;
  std::vector<uint8_t> cross(64 * 48 * 3, 128);
  expectInvalid(decodeEnvironment(encodePng(64, 48, 3, cross), limits, "t", nullptr), "64x48");
}

// ---- real data --------------------------------------------------------------------------

TEST(EnvironmentFiles, BlenderStudioWorldsDecode) {
  // Debian's blender-data 3.4 ships its eight worlds DWAB-compressed.
  const std::filesystem::path dir = "/usr/share/blender/datafiles/studiolights/world";
  if (!std::filesystem::is_directory(dir)) GTEST_SKIP() << dir << " is absent (Debian package blender-data)";
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() != ".exr") continue;
    ++files;
    std::ifstream in(entry.path(), std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    using Clock = std::chrono::steady_clock;
    auto since = [](Clock::time_point start) {
      return int(std::chrono::duration<double, std::milli>(Clock::now() - start).count());
    };
    auto start = Clock::now();
    auto image = decodeExr(bytes, [](int, int) { return Result<void>(); });
    int decodeMs = since(start);
    ASSERT_TRUE(image.ok()) << entry.path() << ": " << image.error().message;
    EnvironmentSource source;
    start = Clock::now();
    auto env = decodeEnvironmentImage(bytes, AssetLimits{}, entry.path().stem().string(), source);
    int totalMs = since(start);
    ASSERT_TRUE(env.ok()) << entry.path() << ": " << env.error().message;
    std::cout << entry.path().filename().string() << ": " << bytes.size() / 1024 << " KiB, " << source.width << "x"
              << source.height << ", faces " << env->faceSize << "; EXR decoded in " << decodeMs
              << " ms, to the cube in " << totalMs << " ms\n";
    EXPECT_EQ(source.format, AssetFormat::Exr);
    EXPECT_EQ(source.width, 2 * source.height);
    expectFiniteAndInRange(*env, 0.0f, 1e9f);
  }
  EXPECT_GT(files, 0) << "no .exr in " << dir;
}

}  // namespace
}  // namespace brdfa
