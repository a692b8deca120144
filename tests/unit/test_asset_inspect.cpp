// Asset inspection: formats told apart by content, each kind's formats, full decoding with
// the real decoders, and the reasons given for everything refused.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "brdfa/assets.h"

#include "image_test_encoders.h"

namespace brdfa {
namespace {

using namespace testing;  // the image encoders

std::string png(int w = 8, int h = 6) { return encodePng(w, h, 3, std::vector<uint8_t>(size_t(w) * h * 3, 90)); }
std::string jpeg(int w = 16, int h = 8) { return encodeJpeg(w, h, 3, std::vector<uint8_t>(size_t(w) * h * 3, 90)); }
std::string hdr(int w = 32, int h = 16, float value = 0.5f) {
  return encodeHdr(w, h, std::vector<float>(size_t(w) * h * 3, value));
}
std::string exr(int w = 32, int h = 16, float value = 0.5f) {
  return encodeExr(w, h, std::vector<float>(size_t(w) * h * 3, value), true);
}
const std::string kQuadObj = "# a quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";

void expectInvalid(const Result<AssetInfo>& r, const std::string& needle) {
  ASSERT_FALSE(r.ok()) << "expected an error mentioning '" << needle << "'";
  EXPECT_EQ(r.error().code, ErrorCode::InvalidArgument);
  EXPECT_NE(r.error().message.find(needle), std::string::npos) << r.error().message;
}

TEST(AssetSniff, ImageMagicNumbers) {
  EXPECT_EQ(sniffAssetFormat(png()), AssetFormat::Png);
  EXPECT_EQ(sniffAssetFormat(jpeg()), AssetFormat::Jpeg);
  EXPECT_EQ(sniffAssetFormat(hdr()), AssetFormat::Hdr);
  EXPECT_EQ(sniffAssetFormat("#?RGBE\nFORMAT=32-bit_rle_rgbe\n\n"), AssetFormat::Hdr);
  EXPECT_EQ(sniffAssetFormat(exr()), AssetFormat::Exr);
  // A prefix of a signature is not the format.
  EXPECT_EQ(sniffAssetFormat(png().substr(0, 4)), std::nullopt);
  EXPECT_EQ(sniffAssetFormat(std::string("\xFF\xD8", 2)), std::nullopt);
  EXPECT_EQ(sniffAssetFormat("#?RADIAN"), std::nullopt);
  EXPECT_EQ(sniffAssetFormat(""), std::nullopt);
}

TEST(AssetSniff, ObjByItsFirstStatement) {
  for (const char* text : {"v 0 0 0\n", "vn 0 1 0\n", "vt 0.5 0.5\n", "f 1 2 3\n", "o cube\n", "g group\n", "s off\n",
                           "l 1 2\n", "p 1\n", "mtllib cube.mtl\n", "usemtl red\n", "v\t1\t2\t3\r\n",
                           "# Blender export\n\n   \n# more\n  v 1 2 3\n", "\r\n\r\nv 1 2 3"})
    EXPECT_EQ(sniffAssetFormat(text), AssetFormat::Obj) << text;
  for (const char* text : {"hello world\n", "vertex 1 2 3\n", "v1 2 3\n", "# only a comment\n", "\n\n", "f\n",
                           "{\"json\": true}", "<svg></svg>", "vp 0.1 0.2\n"})
    EXPECT_EQ(sniffAssetFormat(text), std::nullopt) << text;
  std::string withNul = "v 0 0 0\n" + std::string(1, '\0') + "v 1 1 1\n";
  EXPECT_EQ(sniffAssetFormat(withNul), std::nullopt);
}

TEST(AssetInspect, TexturesReportFormatAndSize) {
  auto p = inspectAsset(png(8, 6), AssetKind::Texture, AssetLimits{});
  ASSERT_TRUE(p.ok()) << p.error().message;
  EXPECT_EQ(p->kind, AssetKind::Texture);
  EXPECT_EQ(p->format, AssetFormat::Png);
  EXPECT_EQ(p->width, 8);
  EXPECT_EQ(p->height, 6);
  auto j = inspectAsset(jpeg(16, 8), AssetKind::Texture, AssetLimits{});
  ASSERT_TRUE(j.ok()) << j.error().message;
  EXPECT_EQ(j->format, AssetFormat::Jpeg);
  EXPECT_EQ(j->width, 16);
  EXPECT_TRUE(j->layout.empty());
}

TEST(AssetInspect, EnvironmentsReportLayoutAndSourceSize) {
  auto h = inspectAsset(hdr(64, 32), AssetKind::Environment, AssetLimits{});
  ASSERT_TRUE(h.ok()) << h.error().message;
  EXPECT_EQ(h->kind, AssetKind::Environment);
  EXPECT_EQ(h->format, AssetFormat::Hdr);
  EXPECT_EQ(h->layout, "equirect");
  EXPECT_EQ(h->width, 64);
  EXPECT_EQ(h->height, 32);
  auto e = inspectAsset(exr(128, 64), AssetKind::Environment, AssetLimits{});
  ASSERT_TRUE(e.ok()) << e.error().message;
  EXPECT_EQ(e->format, AssetFormat::Exr);
  EXPECT_EQ(e->layout, "equirect");
  EXPECT_EQ(e->width, 128);
  auto c = inspectAsset(png(64, 48), AssetKind::Environment, AssetLimits{});
  ASSERT_TRUE(c.ok()) << c.error().message;
  EXPECT_EQ(c->format, AssetFormat::Png);
  EXPECT_EQ(c->layout, "cross");
  EXPECT_EQ(c->width, 64);
  EXPECT_EQ(c->height, 48);
  auto jc = inspectAsset(jpeg(32, 24), AssetKind::Environment, AssetLimits{});
  ASSERT_TRUE(jc.ok()) << jc.error().message;
  EXPECT_EQ(jc->layout, "cross");
}

TEST(AssetInspect, MislabelledFilesNameWhatTheyAre) {
  expectInvalid(inspectAsset(png(), AssetKind::Mesh, AssetLimits{}),
                "mislabelled: the file is a PNG image, not a mesh (OBJ)");
  expectInvalid(inspectAsset(kQuadObj, AssetKind::Texture, AssetLimits{}),
                "mislabelled: the file is an OBJ mesh, not a texture (PNG or JPEG)");
  expectInvalid(inspectAsset(hdr(), AssetKind::Texture, AssetLimits{}),
                "the file is a Radiance HDR image, not a texture");
  expectInvalid(inspectAsset(exr(), AssetKind::Texture, AssetLimits{}), "the file is an OpenEXR image, not a texture");
  expectInvalid(inspectAsset(kQuadObj, AssetKind::Environment, AssetLimits{}), "not an environment");
  expectInvalid(inspectAsset(jpeg(), AssetKind::Mesh, AssetLimits{}), "a JPEG image, not a mesh");
}

TEST(AssetInspect, WrongShapesForEnvironmentsAreRefused) {
  expectInvalid(inspectAsset(hdr(60, 40), AssetKind::Environment, AssetLimits{}), "60x40");
  expectInvalid(inspectAsset(exr(30, 20), AssetKind::Environment, AssetLimits{}), "30x20");
  expectInvalid(inspectAsset(png(100, 100), AssetKind::Environment, AssetLimits{}), "horizontal-cross");
  expectInvalid(inspectAsset(jpeg(64, 64), AssetKind::Environment, AssetLimits{}), "64x64");
}

TEST(AssetInspect, UnrecognisedContentIsRefused) {
  for (AssetKind kind : {AssetKind::Mesh, AssetKind::Texture, AssetKind::Environment})
    expectInvalid(inspectAsset("GIF89a....", kind, AssetLimits{}), "unrecognised file");
  expectInvalid(inspectAsset("", AssetKind::Texture, AssetLimits{}), "expected a texture (PNG or JPEG)");
}

TEST(AssetInspect, LimitsAreChecked) {
  AssetLimits bytes;
  bytes.maxBytes = 10;
  expectInvalid(inspectAsset(png(), AssetKind::Texture, bytes), "the limit is 10 bytes");
  expectInvalid(inspectAsset("0123456789A", AssetKind::Mesh, bytes), "11 bytes");  // before sniffing
  EXPECT_FALSE(inspectAsset(std::string(10, 'x'), AssetKind::Mesh, bytes).error().message.find("limit") !=
               std::string::npos);
  AssetLimits pixels;
  pixels.maxPixels = 100;
  expectInvalid(inspectAsset(png(20, 10), AssetKind::Texture, pixels), "the limit is 100 pixels");
  expectInvalid(inspectAsset(hdr(32, 16), AssetKind::Environment, pixels), "32x16");
  expectInvalid(inspectAsset(exr(32, 16), AssetKind::Environment, pixels), "32x16");
  expectInvalid(inspectAsset(png(64, 48), AssetKind::Environment, pixels), "64x48");
}

TEST(AssetInspect, DamagedFilesAreRefusedWithAReason) {
  const std::string files[] = {png(40, 30), jpeg(64, 48), hdr(64, 32), exr(128, 64)};
  const AssetKind kinds[] = {AssetKind::Texture, AssetKind::Texture, AssetKind::Environment, AssetKind::Environment};
  const char* names[] = {"PNG", "JPEG", "HDR", "EXR"};
  for (int i = 0; i < 4; ++i) {
    const std::string& file = files[i];
    expectInvalid(inspectAsset(file.substr(0, file.size() / 2), kinds[i], AssetLimits{}), names[i]);
  }
  std::vector<float> rgb(size_t(32) * 16 * 3, 0.5f);
  rgb[7] = std::numeric_limits<float>::quiet_NaN();
  expectInvalid(inspectAsset(encodeExr(32, 16, rgb, false), AssetKind::Environment, AssetLimits{}), "NaN");
}

TEST(AssetInspect, MeshesReportWhatTheObjLoaderFound) {
  auto info = inspectAsset(kQuadObj, AssetKind::Mesh, AssetLimits{});
  if (!info.ok() && info.error().code == ErrorCode::Unsupported) GTEST_SKIP() << info.error().message;
  ASSERT_TRUE(info.ok()) << info.error().message;
  EXPECT_EQ(info->kind, AssetKind::Mesh);
  EXPECT_EQ(info->format, AssetFormat::Obj);
  EXPECT_EQ(info->triangles, 2u);
  EXPECT_EQ(info->vertices, 4u);
  EXPECT_TRUE(info->generatedNormals);
}

}  // namespace
}  // namespace brdfa
