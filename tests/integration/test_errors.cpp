// Failure behaviour (docs/design.md section 7): every bad input gets a JSON error with a fitting
// status and leaves the server healthy (ServerTest::TearDown checks /api/health after each).
#include "server_fixture.h"

namespace brdfa::itest {
namespace {

using nlohmann::json;

class BadInput : public ServerTest {
 protected:
  // Asserts status, a JSON body {"error": ..., "message": ...} and, when given, the field.
  static json expectError(const httplib::Result& r, int status, const std::string& field = {}) {
    EXPECT_TRUE(r);
    if (!r) return nullptr;
    EXPECT_EQ(r->status, status) << r->body;
    EXPECT_EQ(r->get_header_value("Content-Type"), "application/json");
    json body = bodyJson(r);
    EXPECT_TRUE(body.is_object()) << r->body;
    if (!body.is_object()) return body;
    EXPECT_TRUE(body.contains("error") && body["error"].is_string()) << r->body;
    EXPECT_TRUE(body.contains("message") && body["message"].is_string()) << r->body;
    if (!field.empty()) {
      EXPECT_EQ(body.value("field", ""), field) << r->body;
    }
    return body;
  }
  static json renderBody(const json& scene, const json& spp = 4) {
    return {{"scene", scene}, {"spp", spp}, {"format", "pfm"}};
  }
  static json small() { return {{"render", {{"width", 16}, {"height", 16}}}}; }
};

TEST_F(BadInput, CompileErrorReportsTheSubmittedLine) {
  for (const char* path : {"/api/brdfs/validate", "/api/brdfs/x"}) {
    SCOPED_TRACE(path);
    auto r = std::string(path) == "/api/brdfs/validate" ? post(path, kSyntaxErrorOnLine9, "text/plain")
                                                        : put(path, kSyntaxErrorOnLine9, "text/plain");
    json body = expectError(r, 422);
    EXPECT_EQ(body.value("error", ""), "compile_error");
    ASSERT_TRUE(body["diagnostics"].is_array() && !body["diagnostics"].empty()) << r->body;
    EXPECT_EQ(body["diagnostics"][0]["line"], 9) << r->body;
    EXPECT_TRUE(body["diagnostics"][0]["message"].is_string());
  }
  // A failed PUT stores nothing.
  expectError(get("/api/brdfs/x"), 404);
  // The same text inline in a one-shot render is a 422 too.
  json req =
      renderBody(json{{"objects", json::array({{{"brdf", "inline"}}})}, {"render", {{"width", 16}, {"height", 16}}}});
  req["brdf_source"] = kSyntaxErrorOnLine9;
  json body = expectError(post("/api/render", req.dump()), 422);
  ASSERT_FALSE(body["diagnostics"].empty());
  EXPECT_EQ(body["diagnostics"][0]["line"], 9);
}

TEST_F(BadInput, MalformedParameterLineIs422WithItsLine) {
  const char* text =
      "analytic\n::begin parameters\nfloat r 0 1 0.5\nfloat broken zero 1 0.5\n::end parameters\n"
      "::begin shader\nvec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return vec3(r); }\n::end shader\n";
  json body = expectError(post("/api/brdfs/validate", text, "text/plain"), 422);
  ASSERT_FALSE(body["diagnostics"].empty());
  EXPECT_EQ(body["diagnostics"][0]["line"], 4);
}

TEST_F(BadInput, BodyThatIsNotJson) {
  EXPECT_EQ(expectError(post("/api/render", "{not json"), 400).value("error", ""), "bad_json");
  EXPECT_EQ(expectError(put("/api/sessions/default/scene", "NaN"), 400).value("error", ""), "bad_json");
  EXPECT_EQ(expectError(patch("/api/sessions/default/scene", ""), 400).value("error", ""), "bad_json");
  // Hostile nesting is refused before any recursive code sees it.
  EXPECT_EQ(expectError(post("/api/render", std::string(100000, '[')), 400).value("error", ""), "bad_json");
}

TEST_F(BadInput, WrongTypesNameTheField) {
  expectError(post("/api/render", renderBody({{"render", {{"width", "big"}}}}).dump()), 400, "render.width");
  expectError(post("/api/render", renderBody({{"camera", {{"position", {0, "x", 3}}}}}).dump()), 400,
              "camera.position[1]");
  expectError(post("/api/render", renderBody({{"environment", {{"visible", "yes"}}}}).dump()), 400,
              "environment.visible");
  expectError(post("/api/render", renderBody({{"objects", json::array({"sphere"})}}).dump()), 400, "objects[0]");
  expectError(post("/api/render", renderBody({{"objects", "sphere"}}).dump()), 400, "objects");
  json params = {{"objects", json::array({{{"brdf", "lambert"}, {"params", {{"Kd", 1}}}}})}};
  expectError(post("/api/render", renderBody(params).dump()), 400, "objects[0].params.Kd");
  params["objects"][0]["params"] = {{"Kd", {1, 1}}};
  expectError(post("/api/render", renderBody(params).dump()), 400, "objects[0].params.Kd");
  params["objects"][0]["params"] = {{"nope", 1}};
  expectError(post("/api/render", renderBody(params).dump()), 400, "objects[0].params.nope");
  // Unknown keys are typos, not silently ignored.
  expectError(post("/api/render", renderBody({{"render", {{"widht", 64}}}}).dump()), 400, "render.widht");
  expectError(put("/api/sessions/default/scene", json{{"camrea", json::object()}}.dump()), 400, "camrea");
  expectError(post("/api/render", renderBody({{"render", {{"sampling", "importance"}}}}).dump()), 400,
              "render.sampling");
}

TEST_F(BadInput, SppOutOfRangeOrNotAnInteger) {
  for (json spp : {json(0), json(-1), json(1e12), json("ten"), json(2.5), json(65537), json(nullptr)}) {
    SCOPED_TRACE(spp.dump());
    expectError(post("/api/render", renderBody(small(), spp).dump()), 400, "spp");
  }
}

TEST_F(BadInput, ImageSizeOutOfRange) {
  for (int size : {8, 5000, 0, -16}) {
    SCOPED_TRACE(size);
    expectError(post("/api/render", renderBody({{"render", {{"width", size}, {"height", 16}}}}).dump()), 400,
                "render.width");
    expectError(post("/api/render", renderBody({{"render", {{"width", 16}, {"height", size}}}}).dump()), 400,
                "render.height");
  }
  expectError(
      post("/api/render", renderBody({{"render", {{"width", 16}, {"height", 16}, {"samples_per_frame", 0}}}}).dump()),
      400, "render.samples_per_frame");
  expectError(
      post("/api/render", renderBody({{"render", {{"width", 16}, {"height", 16}, {"max_samples", 1 << 21}}}}).dump()),
      400, "render.max_samples");
}

TEST_F(BadInput, UnknownNamesAre404) {
  json scene = small();
  scene["objects"] = json::array({{{"brdf", "no_such_brdf"}}});
  expectError(post("/api/render", renderBody(scene).dump()), 404, "objects[0].brdf");
  scene = small();
  scene["environment"] = {{"name", "no_such_env"}};
  expectError(post("/api/render", renderBody(scene).dump()), 404, "environment.name");
  scene = small();
  scene["objects"] = json::array({{{"mesh", "teapot_missing"}}});
  expectError(post("/api/render", renderBody(scene).dump()), 404, "objects[0].mesh");
  expectError(get("/api/sessions/no-such-session/stats"), 404);
  expectError(get("/api/sessions/no-such-session/frame"), 404);
  expectError(del("/api/sessions/no-such-session"), 404);
  expectError(get("/api/brdfs/no_such_brdf"), 404);
  expectError(get("/api/no/such/route"), 404);
  expectError(post("/api/no/such/route", "{}"), 404);
}

TEST_F(BadInput, SceneThatIsNotAnObject) {
  expectError(put("/api/sessions/default/scene", "[1,2]"), 400);
  expectError(post("/api/render", json{{"scene", {1, 2}}, {"spp", 4}}.dump()), 400, "scene");
  expectError(post("/api/render", "[1,2]"), 400);
  expectError(post("/api/sessions", "42"), 400);
  // A merge patch that is not an object replaces the whole scene (RFC 7386), then fails.
  expectError(patch("/api/sessions/default/scene", "[1,2]"), 400);
}

TEST_F(BadInput, NonFiniteAndHugeNumbers) {
  // JSON has no NaN; 1e999 overflows to infinity in the parser.
  auto r = post("/api/render", R"({"spp": 4, "render": {"width": 16, "height": 16}, "camera": {"fov": 1e999}})");
  json body = expectError(r, 400);
  expectError(
      post("/api/render",
           renderBody({{"camera", {{"position", {1e300, 0, 3}}}}, {"render", {{"width", 16}, {"height", 16}}}}).dump()),
      400, "camera.position[0]");
  expectError(
      post("/api/render", renderBody({{"camera", {{"fov", 180}}}, {"render", {{"width", 16}, {"height", 16}}}}).dump()),
      400, "camera.fov");
  expectError(post("/api/render", renderBody({{"environment", {{"intensity", -1}}}}).dump()), 400,
              "environment.intensity");
  expectError(post("/api/render", renderBody({{"render", {{"width", 1e300}}}}).dump()), 400, "render.width");
  json params = {{"objects", json::array({{{"brdf", "ggx"}, {"params", {{"roughness", 1e30}}}}})}};
  expectError(post("/api/render", renderBody(params).dump()), 400, "objects[0].params.roughness");
  expectError(get("/api/sessions/default/frame?min_spp=-3"), 400, "min_spp");
  expectError(get("/api/sessions/default/frame?format=jpeg"), 400, "format");
}

TEST_F(BadInput, SessionRules) {
  EXPECT_EQ(expectError(del("/api/sessions/default"), 409).value("error", ""), "conflict");
  // A failed scene update leaves the previous scene in place.
  auto before = get("/api/sessions/default/scene");
  ASSERT_TRUE(before && before->status == 200);
  expectError(put("/api/sessions/default/scene", json{{"render", {{"width", 8}}}}.dump()), 400, "render.width");
  json patchBody = {{"objects", json::array({{{"brdf", "x"}, {"mesh", "sphere"}}})}};
  expectError(patch("/api/sessions/default/scene", patchBody.dump()), 404, "objects[0].brdf");
  auto after = get("/api/sessions/default/scene");
  ASSERT_TRUE(after && after->status == 200);
  EXPECT_EQ(bodyJson(before), bodyJson(after));
  // "inline" belongs to one-shot renders only.
  expectError(put("/api/sessions/default/scene", json{{"objects", json::array({{{"brdf", "inline"}}})}}.dump()), 400,
              "objects[0].brdf");
  // One-shot "inline" without brdf_source.
  expectError(post("/api/render", renderBody({{"objects", json::array({{{"brdf", "inline"}}})}}).dump()), 400,
              "objects[0].brdf");
}

TEST_F(BadInput, BrdfLibraryRules) {
  expectError(put("/api/brdfs/ggx", kLambertWhite, "text/plain"), 409);
  expectError(del("/api/brdfs/ggx"), 409);
  expectError(put("/api/brdfs/bad.name", kLambertWhite, "text/plain"), 400, "name");
  expectError(put("/api/brdfs/inline", kLambertWhite, "text/plain"), 400, "name");
  expectError(put("/api/brdfs/" + std::string(65, 'a'), kLambertWhite, "text/plain"), 400, "name");
  expectError(put("/api/brdfs/empty", "", "text/plain"), 400);
  expectError(post("/api/brdfs/validate", "", "text/plain"), 400);
  expectError(post("/api/brdfs/validate", "just some words", "text/plain"), 422);
}

TEST_F(BadInput, PayloadTooLarge) {
  std::string big(5u << 20, ' ');
  big[0] = '{';
  big.back() = '}';
  json body = expectError(post("/api/render", big), 413);
  EXPECT_EQ(body.value("error", ""), "payload_too_large");
  std::string bigBrdf(std::string(kLambertWhite) + std::string(1100000, '\n'));
  expectError(post("/api/brdfs/validate", bigBrdf, "text/plain"), 413);
}

TEST_F(BadInput, StaticFilesStayInsideWebRoot) {
  auto r = get("/%2e%2e/%2e%2e/etc/passwd");
  ASSERT_TRUE(r);
  EXPECT_TRUE(r->status == 400 || r->status == 404) << r->status;
  EXPECT_EQ(r->body.find("root:"), std::string::npos);
  r = get("/../CMakeLists.txt");
  ASSERT_TRUE(r);
  EXPECT_TRUE(r->status == 400 || r->status == 404) << r->status;
  EXPECT_EQ(r->body.find("cmake_minimum_required"), std::string::npos);
}

}  // namespace
}  // namespace brdfa::itest
