// Uploads: POST/GET /api/assets against the real server, with real files made here
// (OBJ text, stb_image_write's PNG/JPEG/HDR, the renderer's EXR writer): every type uploads,
// is listed, renders in a scene and survives a restart; bad, mislabelled and oversized files
// are 400s that leave the server working; nothing a client names ever becomes a path.
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>

#include "brdfa/image_codec.h"
#include "image_test_encoders.h"
#include "server_fixture.h"

namespace brdfa::itest {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// ---- Test files ------------------------------------------------------------------------------

// A unit octahedron: 6 vertices, 8 triangles, no normals (the loader computes them).
const char* const kOctahedron =
    "# octahedron\nv 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\n"
    "f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n";

// w x h RGBA8 of one colour, or noise when `noise` (incompressible: a large file).
std::vector<uint8_t> rgba8(int w, int h, std::array<uint8_t, 3> rgb, bool noise = false) {
  std::vector<uint8_t> px(size_t(w) * h * 4);
  uint32_t state = 12345;
  for (size_t i = 0; i < px.size(); i += 4) {
    for (int c = 0; c < 3; ++c) {
      state = state * 1664525u + 1013904223u;
      px[i + c] = noise ? uint8_t(state >> 24) : rgb[c];
    }
    px[i + 3] = 255;
  }
  return px;
}

std::string png(int w, int h, std::array<uint8_t, 3> rgb, bool noise = false) {
  std::vector<uint8_t> bytes = encodePng(rgba8(w, h, rgb, noise).data(), w, h);
  return std::string(bytes.begin(), bytes.end());
}

std::string jpeg(int w, int h, std::array<uint8_t, 3> rgb, bool noise = false) {
  return testing::encodeJpeg(w, h, 4, rgba8(w, h, rgb, noise));
}

std::string hdr(int w, int h, std::array<float, 3> rgb) {
  std::vector<float> px;
  for (int i = 0; i < w * h; ++i) px.insert(px.end(), rgb.begin(), rgb.end());
  return testing::encodeHdr(w, h, px);
}

std::string exr(int w, int h, std::array<float, 3> rgb) {
  std::vector<float> px;
  for (int i = 0; i < w * h; ++i) px.insert(px.end(), {rgb[0], rgb[1], rgb[2], 1.0f});
  std::vector<uint8_t> bytes = encodeExr(px.data(), w, h);
  return std::string(bytes.begin(), bytes.end());
}

// One kind of upload, with what a correct one and a broken one look like.
struct AssetType {
  std::string label;
  std::string kind;  // what the server must report
  std::string format;
  std::string fileName;
  std::string sentKind;  // the `kind` field sent ("" = none)
  std::string contentType;
  std::string bytes;      // a valid file
  std::string truncated;  // cut short
  std::string corrupt;    // damaged inside
  std::string wrongKind;  // a kind the content cannot be
  std::string wrongName;  // a file name whose extension says another format
  std::string wrongType;  // a Content-Type that says another format
};

// Flips 16 bytes from `at` (a fraction of the size).
std::string damaged(std::string bytes, double at) {
  size_t start = size_t(double(bytes.size()) * at);
  for (size_t i = start; i < std::min(bytes.size(), start + 16); ++i) bytes[i] = char(bytes[i] ^ 0x5A);
  return bytes;
}

// A JPEG whose first Huffman table claims more codes than a table can hold (a JPEG's
// entropy-coded data is too forgiving to damage reliably: decoders resynchronise).
std::string corruptJpeg(std::string bytes) {
  const size_t dht = bytes.find("\xFF\xC4");
  if (dht == std::string::npos) return bytes;
  for (size_t i = dht + 5; i < std::min(bytes.size(), dht + 5 + 16); ++i) bytes[i] = char(0xFF);  // 16 code counts
  return bytes;
}

std::vector<AssetType> assetTypes() {
  std::vector<AssetType> types;
  std::string obj = kOctahedron;
  types.push_back({"obj", "mesh", "obj", "octahedron.obj", "", "", obj,
                   obj.substr(0, obj.find("f ")),                                         // vertices, no faces
                   std::string(kOctahedron).replace(obj.find("f 1 3 5"), 7, "f 1 3 99"),  // bad index
                   "texture", "octahedron.png", "image/png"});
  std::string p = png(8, 8, {255, 0, 0});
  types.push_back({"png", "texture", "png", "red.png", "", "image/png", p, p.substr(0, p.size() / 2), damaged(p, 0.6),
                   "mesh", "red.jpg", "image/jpeg"});
  std::string j = jpeg(16, 16, {255, 0, 0});
  types.push_back({"jpeg", "texture", "jpeg", "red.jpeg", "texture", "image/jpeg", j, j.substr(0, j.size() / 2),
                   corruptJpeg(j), "mesh", "red.png", "image/png"});
  std::string h = hdr(32, 16, {0.25f, 0.5f, 1.0f});
  types.push_back({"hdr", "environment", "hdr", "sky.hdr", "", "", h, h.substr(0, h.size() / 2), damaged(h, 0.7),
                   "texture", "sky.exr", "image/png"});
  std::string e = exr(32, 16, {0.75f, 0.5f, 2.0f});
  types.push_back({"exr", "environment", "exr", "sky.exr", "environment", "image/x-exr", e, e.substr(0, e.size() / 2),
                   damaged(e, 0.8), "mesh", "sky.hdr", "image/jpeg"});
  std::string cross = png(64, 48, {128, 128, 128});
  types.push_back({"cross png", "environment", "png", "cross.png", "environment", "", cross,
                   cross.substr(0, cross.size() / 2), damaged(cross, 0.6), "mesh", "cross.obj", "model/obj"});
  return types;
}

// ---- Harness ---------------------------------------------------------------------------------

httplib::MultipartFormDataItems form(const std::string& bytes, const std::string& fileName,
                                     const std::string& contentType = "", const std::string& kind = "") {
  httplib::MultipartFormDataItems items = {{"file", bytes, fileName, contentType}};
  if (!kind.empty()) items.push_back({"kind", kind, "", ""});
  return items;
}

class Assets : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/brdfa-assets-XXXXXX";
    ASSERT_NE(::mkdtemp(tmpl), nullptr);
    root_ = tmpl;
    dataDir_ = root_ + "/data";
  }
  void TearDown() override {
    for (auto& s : servers_)
      if (s->running()) {
        if (HasFailure()) std::fprintf(stderr, "---- server log ----\n%s\n", s->logTail(4000).c_str());
        EXPECT_EQ(s->terminate(), 0);
      }
    std::error_code ec;
    fs::remove_all(root_, ec);
  }

  // A server on this test's data folder (stops the previous one first).
  ServerProcess& start(std::vector<std::string> extra = {}) {
    if (!servers_.empty() && servers_.back()->running()) {
      EXPECT_EQ(servers_.back()->terminate(), 0);
    }
    auto s = std::make_unique<ServerProcess>();
    extra.insert(extra.begin(), {"--data-dir", dataDir_, "--idle-timeout", "3"});
    std::string err = s->start(extra);
    EXPECT_EQ(err, "");
    servers_.push_back(std::move(s));
    return *servers_.back();
  }
  ServerProcess& server() { return *servers_.back(); }

  httplib::Result upload(const httplib::MultipartFormDataItems& items) {
    return server().client()->Post("/api/assets", items);
  }
  json getJson(const std::string& path, int expectStatus = 200) {
    auto r = server().client()->Get(path);
    EXPECT_TRUE(r) << path;
    if (!r) return nullptr;
    EXPECT_EQ(r->status, expectStatus) << path << ": " << r->body;
    return bodyJson(r);
  }
  std::vector<std::string> listedIds(const std::string& query = "") {
    std::vector<std::string> ids;
    for (const json& a : getJson("/api/assets" + query)) ids.push_back(a.value("id", ""));
    return ids;
  }

  // PUTs `scene` on the default session and reads one frame (PFM, at least 1 sample).
  bool renderScene(const json& scene, Image* image = nullptr) {
    auto client = server().client();
    auto put = client->Put("/api/sessions/default/scene", scene.dump(), "application/json");
    EXPECT_TRUE(put && put->status == 200) << (put ? put->body : "no response") << "\n" << scene.dump();
    if (!put || put->status != 200) return false;
    auto frame = client->Get("/api/sessions/default/frame?format=pfm&min_spp=1");
    EXPECT_TRUE(frame && frame->status == 200) << (frame ? frame->body : "no response");
    if (!frame || frame->status != 200) return false;
    Image img;
    EXPECT_TRUE(decodeImage(frame->body, img));
    EXPECT_GE(std::stoi(frame->get_header_value("X-Samples")), 1);
    if (image) *image = img;
    return true;
  }

  void expectHealthyAndRendering() {
    EXPECT_EQ(getJson("/api/health").value("status", ""), "ok");
    Image img;
    ASSERT_TRUE(renderScene(furnaceScene("lambert", {{"Kd", {1, 1, 1}}}, 24, 4), &img));
    EXPECT_NEAR(img.at(12, 12, 0), 1.0f, 1e-4f);
  }

  // The scene that uses asset `id` of `type`.
  static json sceneUsing(const AssetType& type, const std::string& id) {
    json scene = {{"render", {{"width", 24}, {"height", 24}, {"max_samples", 4}, {"samples_per_frame", 2}}}};
    if (type.kind == "mesh") {
      scene["environment"] = {{"name", "furnace"}, {"visible", false}};
      scene["objects"] = json::array({{{"mesh", id}, {"brdf", "lambert"}, {"params", {{"Kd", {1, 1, 1}}}}}});
    } else if (type.kind == "texture") {
      scene["environment"] = {{"name", "furnace"}, {"visible", false}};
      scene["objects"] = json::array({{{"mesh", "sphere"}, {"brdf", "itest_textured"}, {"textures", {id}}}});
    } else {
      scene["environment"] = {{"name", id}, {"visible", true}};
      scene["objects"] = json::array();
    }
    return scene;
  }

  // Renders with `id` and checks the frame shows it: the mesh covers the centre, the red texture
  // makes the sphere red, the constant environment is the background.
  void expectRendersWith(const AssetType& type, const std::string& id) {
    SCOPED_TRACE(type.label + " " + id);
    Image img;
    ASSERT_TRUE(renderScene(sceneUsing(type, id), &img));
    const float r = img.at(12, 12, 0), g = img.at(12, 12, 1), b = img.at(12, 12, 2);
    if (type.kind == "mesh") {
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(img.at(12, 12, c), 1.0f, 1e-4f);  // white furnace
      EXPECT_EQ(img.lum(0, 0), 0.0f);                                           // background hidden
    } else if (type.kind == "texture") {
      EXPECT_GT(r, 0.8f);
      EXPECT_LT(g, 0.1f);
      EXPECT_LT(b, 0.1f);
    } else if (type.format == "hdr") {
      EXPECT_NEAR(r, 0.25f, 0.01f);
      EXPECT_NEAR(g, 0.5f, 0.01f);
      EXPECT_NEAR(b, 1.0f, 0.02f);
    } else if (type.format == "exr") {
      EXPECT_NEAR(r, 0.75f, 0.01f);
      EXPECT_NEAR(g, 0.5f, 0.01f);
      EXPECT_NEAR(b, 2.0f, 0.02f);
    } else {  // a grey cross: grey, whether read as sRGB (0.216) or linear (0.502)
      EXPECT_NEAR(r, g, 1e-3f);
      EXPECT_NEAR(g, b, 1e-3f);
      EXPECT_GT(r, 0.2f);
      EXPECT_LT(r, 0.51f);
    }
  }

  // Asserts a 400 JSON error with a message (and a reason); returns the body.
  json expectRejected(const httplib::Result& r, const std::string& what, int status = 400) {
    EXPECT_TRUE(r) << what;
    if (!r) return nullptr;
    EXPECT_EQ(r->status, status) << what << ": " << r->body;
    json body = bodyJson(r);
    EXPECT_TRUE(body.is_object() && body["error"].is_string() && body["message"].is_string() &&
                !body["message"].get<std::string>().empty())
        << what << ": " << r->body;
    return body;
  }

  std::set<std::string> filesIn(const fs::path& dir) {
    std::set<std::string> names;
    std::error_code ec;
    for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
      names.insert(it->path().filename().string());
    return names;
  }

  std::string root_, dataDir_;
  std::vector<std::unique_ptr<ServerProcess>> servers_;
};

// ---- Tests -----------------------------------------------------------------------------------

TEST_F(Assets, EveryTypeUploadsListsRendersAndSurvivesARestart) {
  start();
  auto brdf = server().client()->Put("/api/brdfs/itest_textured", kTexturedLambert, "text/plain");
  ASSERT_TRUE(brdf && brdf->status == 201) << (brdf ? brdf->body : "");
  std::vector<std::pair<AssetType, std::string>> uploaded;
  for (const AssetType& type : assetTypes()) {
    SCOPED_TRACE(type.label);
    auto r = upload(form(type.bytes, type.fileName, type.contentType, type.sentKind));
    ASSERT_TRUE(r);
    ASSERT_EQ(r->status, 201) << r->body;
    json a = bodyJson(r);
    const std::string id = a.value("id", "");
    EXPECT_TRUE(std::regex_match(id, std::regex("(mesh|tex|env)_[0-9a-f]{16}"))) << id;
    EXPECT_EQ(r->get_header_value("Location"), "/api/assets/" + id);
    EXPECT_EQ(a["kind"], type.kind);
    EXPECT_EQ(a["format"], type.format);
    EXPECT_EQ(a["name"], type.fileName);
    EXPECT_EQ(a["bytes"], type.bytes.size());
    EXPECT_EQ(a["builtin"], false);
    EXPECT_EQ(a["source"], "upload");
    if (type.kind == "mesh") {
      EXPECT_EQ(a["triangles"], 8);
      EXPECT_GE(a["vertices"].get<int>(), 6);
    } else {
      EXPECT_GT(a["width"].get<int>(), 0);
      EXPECT_GT(a["height"].get<int>(), 0);
    }
    if (type.kind == "environment") {
      EXPECT_EQ(a["layout"], type.label == "cross png" ? "cross" : "equirect");
    }
    EXPECT_EQ(getJson("/api/assets/" + id), a);
    auto ofKind = listedIds("?kind=" + type.kind);
    EXPECT_NE(std::find(ofKind.begin(), ofKind.end(), id), ofKind.end());
    expectRendersWith(type, id);
    uploaded.emplace_back(type, id);
  }

  // The listing: built-ins first, marked as such; every upload once.
  json all = getJson("/api/assets");
  ASSERT_TRUE(all.is_array());
  bool sawSphere = false;
  for (const json& a : all)
    if (a["id"] == "sphere") {
      sawSphere = true;
      EXPECT_EQ(a["builtin"], true);
      EXPECT_EQ(a["source"], "builtin");
      EXPECT_EQ(a["kind"], "mesh");
    }
  EXPECT_TRUE(sawSphere);
  EXPECT_EQ(getJson("/api/assets?kind=bogus", 400).value("field", ""), "kind");

  // A second server on the same data folder finds, lists and renders them all.
  start();
  for (const auto& [type, id] : uploaded) {
    SCOPED_TRACE("after restart: " + type.label);
    json a = getJson("/api/assets/" + id);
    EXPECT_EQ(a["kind"], type.kind);
    EXPECT_EQ(a["name"], type.fileName);
    expectRendersWith(type, id);
  }
  // Only generated names in the folder: <id>.<ext> and <id>.json.
  for (const std::string& f : filesIn(dataDir_ + "/assets"))
    EXPECT_TRUE(std::regex_match(f, std::regex("(mesh|tex|env)_[0-9a-f]{16}\\.(obj|png|jpg|hdr|exr|json)"))) << f;
  EXPECT_EQ(filesIn(dataDir_ + "/assets").size(), 2 * uploaded.size());
}

TEST_F(Assets, BadUploadsAre400AndLeaveTheServerWorking) {
  // Limits small enough that ordinary test files exceed them.
  start({"--max-upload-bytes", "1500", "--max-upload-pixels", "1000", "--max-upload-triangles", "4"});
  for (const AssetType& type : assetTypes()) {
    SCOPED_TRACE(type.label);
    const std::string kind = type.sentKind;
    struct Bad {
      std::string what;
      httplib::MultipartFormDataItems items;
      std::string field;
    };
    std::vector<Bad> bad = {
        {"truncated", form(type.truncated, type.fileName, type.contentType, kind), "file"},
        {"corrupt", form(type.corrupt, type.fileName, type.contentType, kind), "file"},
        {"wrong kind", form(type.bytes, type.fileName, "", type.wrongKind), "kind"},
        {"wrong extension", form(type.bytes, type.wrongName, "", kind), "file"},
        {"wrong content type", form(type.bytes, type.fileName, type.wrongType, kind), "file"},
    };
    // Too many bytes: padded (OBJ comments) or noise (images) past 1500 bytes.
    std::string big = type.format == "obj"    ? type.bytes + "#" + std::string(2000, 'x') + "\n"
                      : type.format == "png"  ? png(64, 48, {0, 0, 0}, true)
                      : type.format == "jpeg" ? jpeg(64, 48, {0, 0, 0}, true)
                                              : type.bytes + std::string(2000, '\0');
    bad.push_back({"too many bytes", form(big, type.fileName, "", kind), "file"});
    // Too many triangles or pixels, in a small file.
    if (type.kind == "mesh") {
      bad.push_back({"too many triangles", form(type.bytes, type.fileName, "", kind), "file"});
    } else {
      std::string many = type.format == "hdr"    ? hdr(64, 32, {1, 1, 1})
                         : type.format == "exr"  ? exr(64, 32, {1, 1, 1})
                         : type.format == "jpeg" ? jpeg(40, 30, {255, 0, 0})
                                                 : png(64, 48, {9, 9, 9});
      bad.push_back({"too many pixels", form(many, type.fileName, "", kind), "file"});
    }
    for (const Bad& b : bad) {
      SCOPED_TRACE(b.what);
      json body = expectRejected(upload(b.items), b.what);
      EXPECT_EQ(body.value("field", ""), b.field) << body.dump();
      EXPECT_TRUE(body.contains("reason")) << body.dump();
      if (b.what == "too many bytes") {
        EXPECT_EQ(body.value("reason", ""), "too_large");
        const std::string message = body.value("message", "");
        EXPECT_NE(message.find(std::to_string(big.size())), std::string::npos) << message;
        EXPECT_NE(message.find("1500"), std::string::npos) << message;
      }
      if (b.what.starts_with("wrong")) {
        EXPECT_EQ(body.value("reason", ""), "mislabelled") << body.dump();
      }
      EXPECT_EQ(getJson("/api/health").value("status", ""), "ok");
    }
  }

  // Form mistakes.
  auto client = server().client();
  expectRejected(client->Post("/api/assets", kOctahedron, "text/plain"), "not multipart");
  expectRejected(client->Post("/api/assets", "{}", "application/json"), "json");
  expectRejected(upload({{"kind", "mesh", "", ""}}), "no file part");
  expectRejected(upload(form("", "empty.obj")), "empty file");
  expectRejected(upload(form("hello, world\n", "hello.txt")), "not an asset");
  expectRejected(upload(form(kOctahedron, "a.obj", "", "shader")), "unknown kind");
  auto extra = form(kOctahedron, "a.obj");
  extra.push_back({"colour", "red", "", ""});
  expectRejected(upload(extra), "unknown field");
  auto twice = form(kOctahedron, "a.obj");
  twice.push_back({"file", kOctahedron, "b.obj", ""});
  expectRejected(upload(twice), "two files");

  // Nothing was stored, and the server renders as before.
  EXPECT_TRUE(filesIn(dataDir_ + "/assets").empty());
  expectHealthyAndRendering();
}

TEST_F(Assets, ClientNamesNeverBecomePaths) {
  start();
  // A file name with a path: stored under a generated id, shown by its last component.
  for (std::string name : {"../../etc/passwd", "..\\..\\boot.ini", "/tmp/x/../../escape.obj"}) {
    auto r = upload(form(kOctahedron, name));
    ASSERT_TRUE(r);
    ASSERT_EQ(r->status, 201) << r->body;
    json a = bodyJson(r);
    EXPECT_EQ(a["name"].get<std::string>().find_first_of("/\\"), std::string::npos) << a.dump();
  }
  EXPECT_EQ(bodyJson(upload(form(kOctahedron, "../../etc/passwd")))["name"], "passwd");

  // Ids that are paths: unknown everywhere, and no file is read or made.
  for (std::string bad : {"../../etc/passwd", "..", "/etc/passwd", "mesh_0000000000000000"}) {
    SCOPED_TRACE(bad);
    auto client = server().client();
    json mesh = {{"objects", json::array({{{"mesh", bad}}})}};
    auto r = client->Put("/api/sessions/default/scene", mesh.dump(), "application/json");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 404) << r->body;
    EXPECT_NE(r->body.find("mesh"), std::string::npos);
    json tex = {{"objects", json::array({{{"textures", {bad}}}})}};
    r = client->Put("/api/sessions/default/scene", tex.dump(), "application/json");
    ASSERT_TRUE(r);
    EXPECT_TRUE(r->status == 404 || r->status == 400) << r->body;
    json env = {{"environment", {{"name", bad}}}};
    r = client->Put("/api/sessions/default/scene", env.dump(), "application/json");
    ASSERT_TRUE(r);
    EXPECT_TRUE(r->status == 404 || r->status == 400) << r->body;
  }
  for (std::string path : {"/api/assets/..%2F..%2Fetc%2Fpasswd", "/api/assets/%2Fetc%2Fpasswd",
                           "/api/assets/mesh_0000000000000000", "/api/assets/.."}) {
    auto r = server().client()->Get(path);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 404) << path << ": " << r->body;
    EXPECT_EQ(bodyJson(r).value("error", ""), "not_found") << r->body;
  }

  // The test's folder holds the data folder only, and the assets folder generated names only.
  EXPECT_EQ(filesIn(root_), std::set<std::string>{"data"});
  for (const std::string& f : filesIn(dataDir_ + "/assets"))
    EXPECT_TRUE(std::regex_match(f, std::regex("mesh_[0-9a-f]{16}\\.(obj|json)"))) << f;
  EXPECT_FALSE(fs::exists(dataDir_ + "/etc"));
  expectHealthyAndRendering();
}

TEST_F(Assets, StorageCapsAre507) {
  start({"--max-assets", "1"});
  auto first = upload(form(kOctahedron, "a.obj"));
  ASSERT_TRUE(first);
  ASSERT_EQ(first->status, 201) << first->body;
  json body = expectRejected(upload(form(kOctahedron, "b.obj")), "second upload", 507);
  EXPECT_EQ(body.value("error", ""), "storage_full");
  EXPECT_NE(body.value("message", "").find("--max-assets"), std::string::npos);

  // After a restart the stored bytes count toward --max-assets-bytes.
  const std::string limit = std::to_string(std::string(kOctahedron).size() * 3 / 2);
  start({"--max-assets", "10", "--max-assets-bytes", limit});
  body = expectRejected(upload(form(kOctahedron, "c.obj")), "over the byte budget", 507);
  EXPECT_NE(body.value("message", "").find("--max-assets-bytes"), std::string::npos);
  expectHealthyAndRendering();
}

TEST_F(Assets, BrokenStoredUploadsAreSkippedAtStart) {
  start();
  auto good = upload(form(kOctahedron, "good.obj"));
  auto lost = upload(form(kOctahedron, "lost.obj"));
  ASSERT_TRUE(good && lost && good->status == 201 && lost->status == 201);
  const std::string goodId = bodyJson(good)["id"], lostId = bodyJson(lost)["id"];
  server().terminate();

  const fs::path dir = dataDir_ + "/assets";
  fs::remove(dir / (lostId + ".obj"));                               // metadata without its file
  std::ofstream(dir / "mesh_0123456789abcdef.json") << "{not json";  // garbage metadata
  std::ofstream(dir / "mesh_0123456789abcdef.obj") << kOctahedron;
  std::ofstream(dir / "mesh_1111111111111111.obj") << kOctahedron;                    // file without metadata
  std::ofstream(dir / (std::string(".tmp-") + goodId + ".obj.abc123")) << "partial";  // interrupted write
  std::ofstream(dir / "mesh_2222222222222222.obj") << kOctahedron;  // another replica's upload in progress
  // Left by a crash long ago (younger files may be another replica's write in progress).
  const auto longAgo = fs::file_time_type::clock::now() - std::chrono::hours(1);
  for (const char* old : {"mesh_1111111111111111.obj", ".tmp-"})
    for (const auto& f : fs::directory_iterator(dir))
      if (f.path().filename().string().rfind(old, 0) == 0) fs::last_write_time(f.path(), longAgo);

  start();
  auto ids = listedIds("?kind=mesh");
  EXPECT_NE(std::find(ids.begin(), ids.end(), goodId), ids.end());
  for (const std::string& id : {lostId, std::string("mesh_0123456789abcdef"), std::string("mesh_1111111111111111")}) {
    EXPECT_EQ(std::find(ids.begin(), ids.end(), id), ids.end()) << id;
    getJson("/api/assets/" + id, 404);
  }
  EXPECT_FALSE(fs::exists(dir / "mesh_1111111111111111.obj"));  // never acknowledged: removed
  EXPECT_FALSE(fs::exists(dir / (std::string(".tmp-") + goodId + ".obj.abc123")));
  EXPECT_TRUE(fs::exists(dir / "mesh_2222222222222222.obj")) << "a young file may be another replica's write";
  EXPECT_NE(server().logTail().find(lostId), std::string::npos);
  expectRendersWith(assetTypes()[0], goodId);
}

TEST_F(Assets, EnvironmentFoldersGiveReadOnlyWorlds) {
  const fs::path worlds = root_ + "/worlds";
  fs::create_directories(worlds);
  std::string bytes = exr(32, 16, {0.75f, 0.5f, 2.0f});
  std::ofstream(worlds / "My World.exr", std::ios::binary) << bytes;
  std::ofstream(worlds / "notes.txt") << "not a world";
  start({"--environment-dir", worlds.string()});
  json a = getJson("/api/assets/blender_my_world");
  EXPECT_EQ(a["kind"], "environment");
  EXPECT_EQ(a["source"], "blender-data");
  EXPECT_EQ(a["builtin"], true);
  EXPECT_EQ(a.dump().find(worlds.string()), std::string::npos) << "the path is not exposed";
  auto ids = listedIds("?kind=environment");
  EXPECT_NE(std::find(ids.begin(), ids.end(), "blender_my_world"), ids.end());
  EXPECT_EQ(std::find(ids.begin(), ids.end(), "blender_notes"), ids.end());
  expectRendersWith(assetTypes()[4], "blender_my_world");  // the same constant as the EXR upload

  // Worlds are decoded on first use, not at start-up (which must not grow with what is
  // installed): one the EXR reader cannot decode is listed, and a scene using it is a 400
  // naming it and the reason; the server stays healthy and the other worlds keep working.
  std::ofstream(worlds / "broken.exr", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  start({"--environment-dir", worlds.string()});
  getJson("/api/assets/blender_broken");
  json brokenScene = {{"environment", {{"name", "blender_broken"}}},
                      {"render", {{"width", 24}, {"height", 24}, {"max_samples", 2}}}};
  auto r = server().client()->Put("/api/sessions/default/scene", brokenScene.dump(), "application/json");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 400) << r->body;
  EXPECT_NE(r->body.find("blender_broken"), std::string::npos) << r->body;
  EXPECT_EQ(server().client()->Get("/api/health")->status, 200);
  getJson("/api/assets/blender_my_world");
  expectRendersWith(assetTypes()[4], "blender_my_world");

  // Without the flag: Debian blender-data's eight worlds (DWAB-compressed EXRs, read through
  // OpenEXR), when the package is installed: each is listed, and one renders.
  const fs::path debian = "/usr/share/blender/datafiles/studiolights/world";
  if (!fs::exists(debian / "forest.exr")) GTEST_SKIP() << "blender-data is not installed";
  start();
  for (const char* world : {"city", "courtyard", "forest", "interior", "night", "studio", "sunrise", "sunset"}) {
    auto r = server().client()->Get(std::string("/api/assets/blender_") + world);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 200) << world << ": " << r->body << "\n" << server().logTail();
    if (r->status == 200) {
      EXPECT_EQ(bodyJson(r)["source"], "blender-data");
    }
  }
  EXPECT_TRUE(renderScene({{"environment", {{"name", "blender_forest"}}},
                           {"render", {{"width", 24}, {"height", 24}, {"max_samples", 2}}}}));
}

}  // namespace
}  // namespace brdfa::itest
