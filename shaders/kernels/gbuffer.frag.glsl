// Visibility pass: writes what shading needs per pixel, in the two planes described in
// shaders/lib/bindings.glsl (surface: id and normal; detail: tangent and texCoord).
layout(location = 1) in vec3 inNormal;
layout(location = 2) in vec2 inTexCoord;
layout(location = 3) in vec4 inTangent;

layout(set = 1, binding = 1) uniform BrdfaObject {
  mat4 model;
  mat4 normalMatrix;
  vec4 id;
} brdfa_object;

layout(location = 0) out uvec2 outSurface;
layout(location = 1) out uvec4 outDetail;

void main() {
  // Surfaces are two-sided: a back face is shaded with its normal turned to the viewer.
  vec3 n = inNormal * (gl_FrontFacing ? 1.0 : -1.0);
  // guard: a degenerate normal (zero-area or broken mesh normals) would encode as NaN; +z
  // stands in, as a normalize of it would have given NaN and a black pixel before.
  if (!(dot(n, n) > 1e-20)) n = vec3(0.0, 0.0, 1.0);
  uint id = uint(brdfa_object.id.x + 0.5) | (inTangent.w < 0.0 ? BRDFA_LEFT_HANDED : 0u);
  outSurface = uvec2(id, brdfa_octEncode(n));
  // guard: meshes without UVs have zero tangents; the shade kernel then builds its frame from N
  // alone (lib/frame.glsl), as it did for a zero tangent before.
  bool missingTangent = !(dot(inTangent.xyz, inTangent.xyz) > 1e-20);
  uint tangent = missingTangent ? 0u : brdfa_octEncode(inTangent.xyz);
  outDetail = uvec4(tangent, floatBitsToUint(inTexCoord), missingTangent ? 1u : 0u);
}
